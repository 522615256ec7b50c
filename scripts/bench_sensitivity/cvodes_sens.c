/* CVODES forward sensitivities, the peer of `lagc run --sensitivity`
 * (docs/BENCHMARKS.md §15). The model comes from a header that
 * scripts/bench_sensitivity.py generates from its SymPy derivation
 * (scripts/bench_sensitivity/models.py), included as MODEL_H: NX state
 * components, NC sensitivity columns, the span T0..T1, the start X0 and
 * S0, and three functions: the right side, its Jacobian J = df/dx and the
 * columns' df/d(column) (zero for a stated value). CVODES gets the exact
 * sensitivity right side fS = J s + df/d(column), CV_SIMULTANEOUS, errconS
 * on, the same rtol and atol for state and sensitivities. Adams with
 * fixed-point iteration (non-stiff) or BDF with Newton and the exact dense
 * Jacobian, by argument.
 *
 * usage: cvodes_sens adams|bdf RTOL ATOL REPEAT
 * prints: the fastest solve's time (s), the steps, then the state and the
 * NC columns at the end time, one number a line. */
#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include MODEL_H

static int rhs(double t, N_Vector y, N_Vector yd, void *u) {
  (void)u;
  model_f(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yd));
  return 0;
}

static int jac(double t, N_Vector y, N_Vector fy, SUNMatrix A, void *u,
               N_Vector a, N_Vector b, N_Vector c) {
  double j[NX * NX];
  (void)fy; (void)u; (void)a; (void)b; (void)c;
  model_jac(t, N_VGetArrayPointer(y), j);
  for (int r = 0; r < NX; r++)
    for (int k = 0; k < NX; k++) SM_ELEMENT_D(A, r, k) = j[r * NX + k];
  return 0;
}

/* fS for every column at once: the Jacobian and df/d(column) once a call. */
static int sens_rhs(int ns, double t, N_Vector y, N_Vector yd, N_Vector *s,
                    N_Vector *sd, void *u, N_Vector a, N_Vector b) {
  double *x = N_VGetArrayPointer(y), j[NX * NX], fp[NC * NX];
  (void)yd; (void)u; (void)a; (void)b;
  model_jac(t, x, j);
  model_fp(t, x, fp);
  for (int c = 0; c < ns; c++) {
    double *v = N_VGetArrayPointer(s[c]), *o = N_VGetArrayPointer(sd[c]);
    for (int r = 0; r < NX; r++) {
      double acc = fp[c * NX + r];
      for (int k = 0; k < NX; k++) acc += j[r * NX + k] * v[k];
      o[r] = acc;
    }
  }
  return 0;
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
  if (argc != 5) {
    fprintf(stderr, "usage: %s adams|bdf RTOL ATOL REPEAT\n", argv[0]);
    return 2;
  }
  int bdf = strcmp(argv[1], "bdf") == 0;
  double rtol = atof(argv[2]), atol = atof(argv[3]);
  int repeat = atoi(argv[4]);
  double best = 1e300, out[NX * (1 + NC)];
  long steps = 0;
  SUNContext ctx;
  SUNContext_Create(NULL, &ctx);
  for (int rep = 0; rep <= repeat; rep++) {
    double start = now();
    N_Vector y = N_VNew_Serial(NX, ctx);
    double *x = N_VGetArrayPointer(y);
    for (int i = 0; i < NX; i++) x[i] = X0[i];
    void *mem = CVodeCreate(bdf ? CV_BDF : CV_ADAMS, ctx);
    CVodeInit(mem, rhs, T0, y);
    CVodeSStolerances(mem, rtol, atol);
    CVodeSetMaxNumSteps(mem, 10000000);
    SUNMatrix A = NULL;
    SUNLinearSolver LS = NULL;
    SUNNonlinearSolver NLS = NULL, NLSS = NULL;
    if (bdf) {
      A = SUNDenseMatrix(NX, NX, ctx);
      LS = SUNLinSol_Dense(y, A, ctx);
      CVodeSetLinearSolver(mem, LS, A);
      CVodeSetJacFn(mem, jac);
    } else {
      NLS = SUNNonlinSol_FixedPoint(y, 0, ctx);
      CVodeSetNonlinearSolver(mem, NLS);
    }
    N_Vector *s = N_VCloneVectorArray(NC, y);
    for (int c = 0; c < NC; c++)
      for (int i = 0; i < NX; i++) N_VGetArrayPointer(s[c])[i] = S0[c][i];
    CVodeSensInit(mem, NC, CV_SIMULTANEOUS, sens_rhs, s);
    double abstol[NC];
    for (int c = 0; c < NC; c++) abstol[c] = atol;
    CVodeSensSStolerances(mem, rtol, abstol);
    CVodeSetSensErrCon(mem, SUNTRUE);
    if (!bdf) {
      NLSS = SUNNonlinSol_FixedPointSens(NC + 1, y, 0, ctx);
      CVodeSetNonlinearSolverSensSim(mem, NLSS);
    }
    double t;
    int flag = CVode(mem, T1, y, &t, CV_NORMAL);
    if (flag < 0) { fprintf(stderr, "CVode failed: %d\n", flag); return 1; }
    CVodeGetSens(mem, &t, s);
    for (int i = 0; i < NX; i++) out[i] = x[i];
    for (int c = 0; c < NC; c++)
      for (int i = 0; i < NX; i++) out[NX * (1 + c) + i] = N_VGetArrayPointer(s[c])[i];
    CVodeGetNumSteps(mem, &steps);
    N_VDestroyVectorArray(s, NC);
    N_VDestroy(y);
    CVodeFree(&mem);
    if (A) SUNMatDestroy(A);
    if (LS) SUNLinSolFree(LS);
    if (NLS) SUNNonlinSolFree(NLS);
    if (NLSS) SUNNonlinSolFree(NLSS);
    double took = now() - start;
    if (rep > 0 && took < best) best = took; /* rep 0: warm-up */
  }
  printf("%.9e\n%ld\n", best, steps);
  for (int i = 0; i < NX * (1 + NC); i++) printf("%.17e\n", out[i]);
  SUNContext_Free(&ctx);
  return 0;
}
