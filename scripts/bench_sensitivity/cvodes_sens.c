/* CVODES forward sensitivities, the peer of `lagc run --sensitivity`
 * (docs/BENCHMARKS.md §13). Two models with the same equations as
 * oscillator.lag and pendulum.lag, five sensitivity columns each (two
 * initial values, three params), the exact sensitivity right side given
 * (fS: J s + df/dp), errconS on, the same rtol and atol for state and
 * sensitivities. Adams with fixed-point iteration (non-stiff) or BDF with
 * Newton and a dense exact Jacobian, by argument.
 *
 * usage: cvodes_sens MODEL adams|bdf RTOL ATOL REPEAT
 * prints: the fastest solve's time (s), then the state and the 5 columns
 * at the end time, one number a line. */
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

#define NS 5
static int pendulum;
static double P[3];

static int rhs(double t, N_Vector y, N_Vector yd, void *u) {
  double *x = N_VGetArrayPointer(y), *d = N_VGetArrayPointer(yd);
  (void)t; (void)u;
  if (pendulum) { /* g, l, c */
    d[0] = x[1];
    d[1] = -(P[0] / P[1]) * sin(x[0]) - P[2] * x[1] / (P[1] * P[1]);
  } else { /* m, k, c */
    d[0] = x[1];
    d[1] = -(P[1] * x[0] + P[2] * x[1]) / P[0];
  }
  return 0;
}

static void jacobian(const double *x, double j[2][2]) {
  j[0][0] = 0; j[0][1] = 1;
  if (pendulum) {
    j[1][0] = -(P[0] / P[1]) * cos(x[0]);
    j[1][1] = -P[2] / (P[1] * P[1]);
  } else {
    j[1][0] = -P[1] / P[0];
    j[1][1] = -P[2] / P[0];
  }
}

static void param_partials(const double *x, double dp[3]) {
  if (pendulum) {
    double l = P[1];
    dp[0] = -sin(x[0]) / l;
    dp[1] = P[0] * sin(x[0]) / (l * l) + 2 * P[2] * x[1] / (l * l * l);
    dp[2] = -x[1] / (l * l);
  } else {
    double m = P[0];
    dp[0] = (P[1] * x[0] + P[2] * x[1]) / (m * m);
    dp[1] = -x[0] / m;
    dp[2] = -x[1] / m;
  }
}

static int jac(double t, N_Vector y, N_Vector fy, SUNMatrix J, void *u,
               N_Vector a, N_Vector b, N_Vector c) {
  double j[2][2];
  (void)t; (void)fy; (void)u; (void)a; (void)b; (void)c;
  jacobian(N_VGetArrayPointer(y), j);
  for (int r = 0; r < 2; r++)
    for (int k = 0; k < 2; k++) SM_ELEMENT_D(J, r, k) = j[r][k];
  return 0;
}

static int sens_rhs(int ns, double t, N_Vector y, N_Vector yd, N_Vector *s,
                    N_Vector *sd, void *u, N_Vector a, N_Vector b) {
  double *x = N_VGetArrayPointer(y), j[2][2], dp[3];
  (void)t; (void)yd; (void)u; (void)a; (void)b;
  jacobian(x, j);
  param_partials(x, dp);
  for (int c = 0; c < ns; c++) {
    double *v = N_VGetArrayPointer(s[c]), *o = N_VGetArrayPointer(sd[c]);
    o[0] = j[0][0] * v[0] + j[0][1] * v[1];
    o[1] = j[1][0] * v[0] + j[1][1] * v[1] + (c >= 2 ? dp[c - 2] : 0.0);
  }
  return 0;
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
  if (argc != 6) {
    fprintf(stderr, "usage: %s oscillator|pendulum adams|bdf RTOL ATOL REPEAT\n", argv[0]);
    return 2;
  }
  pendulum = strcmp(argv[1], "pendulum") == 0;
  int bdf = strcmp(argv[2], "bdf") == 0;
  double rtol = atof(argv[3]), atol = atof(argv[4]);
  int repeat = atoi(argv[5]);
  double t1 = pendulum ? 10.0 : 20.0;
  if (pendulum) { P[0] = 9.81; P[1] = 1.0; P[2] = 0.1; }
  else { P[0] = 1.0; P[1] = 4.0; P[2] = 0.4; }
  double best = 1e300, out[2 + 2 * NS];
  long steps = 0;
  SUNContext ctx;
  SUNContext_Create(NULL, &ctx);
  for (int rep = 0; rep <= repeat; rep++) {
    double start = now();
    N_Vector y = N_VNew_Serial(2, ctx);
    double *x = N_VGetArrayPointer(y);
    x[0] = 1.0; x[1] = 0.0;
    void *mem = CVodeCreate(bdf ? CV_BDF : CV_ADAMS, ctx);
    CVodeInit(mem, rhs, 0.0, y);
    CVodeSStolerances(mem, rtol, atol);
    CVodeSetMaxNumSteps(mem, 10000000);
    SUNMatrix A = NULL;
    SUNLinearSolver LS = NULL;
    SUNNonlinearSolver NLS = NULL, NLSS = NULL;
    if (bdf) {
      A = SUNDenseMatrix(2, 2, ctx);
      LS = SUNLinSol_Dense(y, A, ctx);
      CVodeSetLinearSolver(mem, LS, A);
      CVodeSetJacFn(mem, jac);
    } else {
      NLS = SUNNonlinSol_FixedPoint(y, 0, ctx);
      CVodeSetNonlinearSolver(mem, NLS);
    }
    N_Vector *s = N_VCloneVectorArray(NS, y);
    for (int c = 0; c < NS; c++) {
      N_VConst(0.0, s[c]);
      if (c < 2) N_VGetArrayPointer(s[c])[c] = 1.0;
    }
    CVodeSensInit(mem, NS, CV_SIMULTANEOUS, sens_rhs, s);
    double abstol[NS];
    for (int c = 0; c < NS; c++) abstol[c] = atol;
    CVodeSensSStolerances(mem, rtol, abstol);
    CVodeSetSensErrCon(mem, SUNTRUE);
    if (!bdf) {
      NLSS = SUNNonlinSol_FixedPointSens(NS + 1, y, 0, ctx);
      CVodeSetNonlinearSolverSensSim(mem, NLSS);
    }
    double t;
    int flag = CVode(mem, t1, y, &t, CV_NORMAL);
    if (flag < 0) { fprintf(stderr, "CVode failed: %d\n", flag); return 1; }
    CVodeGetSens(mem, &t, s);
    out[0] = x[0]; out[1] = x[1];
    for (int c = 0; c < NS; c++) {
      out[2 + 2 * c] = N_VGetArrayPointer(s[c])[0];
      out[3 + 2 * c] = N_VGetArrayPointer(s[c])[1];
    }
    CVodeGetNumSteps(mem, &steps);
    N_VDestroyVectorArray(s, NS);
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
  for (int i = 0; i < 2 + 2 * NS; i++) printf("%.17e\n", out[i]);
  SUNContext_Free(&ctx);
  return 0;
}
