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
 * Jacobian, by argument. A model with an impact (NEVENT 1) has its switching
 * function as a root, direction down; at each root the state is reset,
 * the columns jump (impact, the formula docs/SENSITIVITY.md states) and
 * CVODES is re-initialized there.
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

#if NEVENT
static int groot(double t, N_Vector y, double *g, void *u) {
  (void)u;
  model_g(t, N_VGetArrayPointer(y), g);
  return 0;
}

/* The impact at t: x <- R(x), and every column jumps by
 * dtau = -(g_x s + g_c) / (g_x f- + g_t), s <- R_x s + R_c + (R_x f- - f+) dtau. */
static void impact(double t, double *x, N_Vector *s) {
  double fm[NX], fp[NX], e[NX + 1 + NC], r[NX + NX * NX + NC * NX], jf[NX];
  model_f(t, x, fm);
  model_gd(t, x, e);
  model_reset(t, x, r);
  for (int i = 0; i < NX; i++) x[i] = r[i];
  model_f(t, x, fp);
  const double *rx = r + NX, *rp = r + NX + NX * NX;
  double den = e[NX];
  for (int k = 0; k < NX; k++) den += e[k] * fm[k];
  for (int i = 0; i < NX; i++) {
    jf[i] = -fp[i];
    for (int k = 0; k < NX; k++) jf[i] += rx[i * NX + k] * fm[k];
  }
  for (int c = 0; c < NC; c++) {
    double *v = N_VGetArrayPointer(s[c]), w[NX], num = e[NX + 1 + c];
    for (int k = 0; k < NX; k++) num += e[k] * v[k];
    double dtau = -num / den;
    for (int i = 0; i < NX; i++) {
      w[i] = rp[c * NX + i] + jf[i] * dtau;
      for (int k = 0; k < NX; k++) w[i] += rx[i * NX + k] * v[k];
    }
    for (int i = 0; i < NX; i++) v[i] = w[i];
  }
}
#endif

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
#if NEVENT
    int down = -1; /* g falls through zero */
    CVodeRootInit(mem, 1, groot);
    CVodeSetRootDirection(mem, &down);
#endif
    double t;
    int flag = CVode(mem, T1, y, &t, CV_NORMAL);
#if NEVENT
    long s_total = 0, s_part;
    while (flag == CV_ROOT_RETURN) {
      CVodeGetSens(mem, &t, s);
      impact(t, x, s);
      CVodeGetNumSteps(mem, &s_part);
      s_total += s_part;
      CVodeReInit(mem, t, y);
      CVodeSensReInit(mem, CV_SIMULTANEOUS, s);
      flag = CVode(mem, T1, y, &t, CV_NORMAL);
    }
#endif
    if (flag < 0) { fprintf(stderr, "CVode failed: %d\n", flag); return 1; }
    CVodeGetSens(mem, &t, s);
    for (int i = 0; i < NX; i++) out[i] = x[i];
    for (int c = 0; c < NC; c++)
      for (int i = 0; i < NX; i++) out[NX * (1 + c) + i] = N_VGetArrayPointer(s[c])[i];
    CVodeGetNumSteps(mem, &steps);
#if NEVENT
    steps += s_total;
#endif
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
