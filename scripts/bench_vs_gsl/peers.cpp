// The compiled peers of scripts/bench_vs_gsl.py: GSL's rk8pd (Prince-Dormand
// 8(7), gsl_odeiv2 driver) and Boost odeint's runge_kutta_fehlberg78
// (controlled) and runge_kutta_dopri5 (dense output) on the reduced systems
// (7) of four lagc models: each the generated crate's `rhs` (lagc build,
// target/bench-gsl/<model>/src/lib.rs) translated line by line to C++ — the
// same expressions in the same order, the same libm calls; parameters are
// compile-time constants here, fields of the model there.
//
// Usage: peers MODEL STEPPER RTOL ATOL SAMPLES REPEAT
//   STEPPER: rk8pd | rkf78 | dopri5
// Prints the samples as CSV (t, x...) on stdout and, on stderr, one line of
// JSON: the smallest in-process wall time of REPEAT solves (after one
// warm-up solve whose samples are printed), and the RHS evaluations.
//
// Build: g++ -O2 -std=c++17 peers.cpp -lgsl -lgslcblas -lm
#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include <boost/numeric/odeint.hpp>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

static long evaluations = 0;

// paper.lag: x = (q1, q2, q1', q2').
static void paper(double t, const double* x, double* dx) {
    const double alpha = 0.5;
    double q1_d1 = x[2];
    double e_3 = 1.0 / (1.0 + t * t);
    dx[0] = x[2];
    dx[1] = x[3];
    dx[2] = (alpha - t * e_3) * q1_d1;
    dx[3] = (alpha * t + e_3) * q1_d1;
}

// knife_edge.lag: x = (x, y, theta, x', y', theta').
static void knife_edge(double, const double* x, double* dx) {
    double x_d1 = x[3], theta = x[2], theta_d1 = x[5];
    double c = std::cos(theta);
    double e_7 = 1.0 / (c * c);  // theta.cos().powi(-2)
    double e_8 = std::tan(theta);
    double e_9 = 1.0 / (1.0 + e_8 * e_8);
    dx[0] = x[3];
    dx[1] = x[4];
    dx[2] = x[5];
    dx[3] = -e_7 * e_8 * e_9 * x_d1 * theta_d1;
    dx[4] = e_7 * e_9 * x_d1 * theta_d1;
    dx[5] = 0.0;
}

// vertical_rocket.lag: x = (z, z').
static void vertical_rocket(double t, const double* x, double* dx) {
    const double m0 = 1000, mu = 10, w = 2000, g = 9.81;
    dx[0] = x[1];
    dx[1] = -g + mu * w / (m0 - mu * t);
}

// pendulum_3.lag (scripts/gen_pendulum.py 3): x = (th1..th3, th1'..th3').
// The generated crate's `mass_system` and `highest` translated line by
// line (target/bench-gsl/pendulum_3/src/lib.rs): the same expressions, the
// same three sincos calls (lagc_runtime::math::sin_cos is glibc's sincos),
// the symmetric mass matrix solved by L D L^T as lagc_runtime's
// ldlt_fixed, with its pivot-ratio check (1e-10) and Gaussian elimination
// with partial pivoting as the fallback (solve_fixed; never taken on this
// motion).
static bool ldlt3(double a[3][3], double b[3]) {
    const int N = 3;
    double d[N], inverse[N], w[N];
    double small = INFINITY, large = 0.0;
    for (int j = 0; j < N; j++) {
        double pivot = a[j][j];
        for (int k = 0; k < j; k++) {
            double v = a[j][k] * d[k];
            w[k] = v;
            pivot -= a[j][k] * v;
        }
        if (!(pivot > 0.0) || !std::isfinite(pivot)) return false;
        small = std::fmin(small, pivot);
        large = std::fmax(large, pivot);
        d[j] = pivot;
        double r = 1.0 / pivot;
        inverse[j] = r;
        for (int i = j + 1; i < N; i++) {
            double s = a[i][j];
            for (int k = 0; k < j; k++) s -= a[i][k] * w[k];
            a[i][j] = s * r;
        }
    }
    for (int i = 0; i < N; i++) {
        double s = b[i];
        for (int k = 0; k < i; k++) s -= a[i][k] * b[k];
        b[i] = s;
    }
    for (int i = 0; i < N; i++) b[i] *= inverse[i];
    for (int i = N - 1; i >= 0; i--) {
        double s = b[i];
        for (int k = i + 1; k < N; k++) s -= a[k][i] * b[k];
        b[i] = s;
    }
    for (int i = 0; i < N; i++)
        if (!std::isfinite(b[i])) return false;
    return small / large >= 1e-10;
}

static void gauss3(double a[3][3], double b[3]) {
    const int N = 3;
    for (int k = 0; k < N; k++) {
        int p = k;
        for (int i = k + 1; i < N; i++)
            if (std::fabs(a[i][k]) > std::fabs(a[p][k])) p = i;
        if (p != k) {
            for (int j = 0; j < N; j++) std::swap(a[k][j], a[p][j]);
            std::swap(b[k], b[p]);
        }
        for (int i = k + 1; i < N; i++) {
            double l = a[i][k] / a[k][k];
            for (int j = k + 1; j < N; j++) a[i][j] -= l * a[k][j];
            b[i] -= l * b[k];
        }
    }
    for (int k = N - 1; k >= 0; k--) {
        double v = b[k];
        for (int j = k + 1; j < N; j++) v -= a[k][j] * b[j];
        b[k] = v / a[k][k];
    }
}

static void pendulum_3(double, const double* x, double* dx) {
    const double g_2 = 9.81;
    double th1 = x[0], th1_d1 = x[3], th2 = x[1], th2_d1 = x[4], th3 = x[2], th3_d1 = x[5];
    double e, e_2, e_4, e_5, e_8, e_9;
    sincos(th1, &e, &e_2);
    double e_3 = th1_d1 * th1_d1;
    sincos(th2, &e_4, &e_5);
    double e_6 = th2_d1 * th2_d1;
    double e_7 = e_2 * e_3 + e_5 * e_6;
    sincos(th3, &e_8, &e_9);
    double e_10 = th3_d1 * th3_d1;
    double e_11 = e_7 + e_9 * e_10;
    double e_12 = -e * e_3 - e_4 * e_6;
    double e_13 = e_12 - e_8 * e_10;
    double e_14 = 2.0 * e * e_4 + 2.0 * e_2 * e_5;
    double e_15 = e * e_8 + e_2 * e_9;
    double e_16 = e_4 * e_8 + e_5 * e_9;
    double a[3][3] = {{3.0, e_14, e_15}, {e_14, 2.0, e_16}, {e_15, e_16, 1.0}};
    double g[3] = {
        3.0 * g_2 * e + e * e_7 + e * e_11 + e_2 * e_12 + e_2 * e_13,
        2.0 * g_2 * e_4 + e_4 * e_7 + e_4 * e_11 + e_5 * e_12 + e_5 * e_13,
        g_2 * e_8 + e_8 * e_11 + e_9 * e_13,
    };
    double z[3] = {-g[0], -g[1], -g[2]};
    double a_ldlt[3][3];
    std::memcpy(a_ldlt, a, sizeof a);
    if (!ldlt3(a_ldlt, z)) {
        z[0] = -g[0], z[1] = -g[1], z[2] = -g[2];
        gauss3(a, z);
    }
    dx[0] = x[3];
    dx[1] = x[4];
    dx[2] = x[5];
    dx[3] = z[0];
    dx[4] = z[1];
    dx[5] = z[2];
}

struct Model {
    const char* name;
    void (*f)(double, const double*, double*);
    int n;
    double t0, t1;
    double y0[6];
};

static const Model MODELS[] = {
    {"paper", paper, 4, 0.0, 5.0, {0, 0, 1, 0}},
    {"knife_edge", knife_edge, 6, 0.0, 2.0, {0, 0, 0, 1, 0, 0.5}},
    {"vertical_rocket", vertical_rocket, 2, 0.0, 80.0, {0, 0}},
    {"pendulum_3", pendulum_3, 6, 0.0, 10.0, {0.1, 0.2, 0.3, 0, 0, 0}},
};

static const Model* model;

static int gsl_rhs(double t, const double y[], double f[], void*) {
    evaluations++;
    model->f(t, y, f);
    return GSL_SUCCESS;
}

typedef std::vector<double> state;

struct OdeintRhs {
    void operator()(const state& x, state& dx, double t) const {
        evaluations++;
        model->f(t, x.data(), dx.data());
    }
};

// Samples: `count` evenly spaced times over [t0, t1] (as lagc's
// sample_times), the first the initial state.
static std::vector<double> sample_times(int count) {
    std::vector<double> times;
    if (count == 1) {
        times.push_back(model->t1);
        return times;
    }
    for (int i = 0; i < count; i++)
        times.push_back(i == count - 1 ? model->t1
                                       : model->t0 + i * (model->t1 - model->t0) / (count - 1));
    return times;
}

// One solve: fills `out` (times.size() rows of n).
static int solve(const char* stepper, double rtol, double atol, const std::vector<double>& times,
                 std::vector<double>& out) {
    int n = model->n;
    out.assign(times.size() * n, 0.0);
    if (std::strcmp(stepper, "rk8pd") == 0) {
        gsl_odeiv2_system sys = {gsl_rhs, nullptr, (size_t)n, nullptr};
        // The driver's first step guess: GSL has no estimate of its own;
        // 1e-6 as in its examples (the controller grows it quickly).
        gsl_odeiv2_driver* d = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-6, atol, rtol);
        double t = model->t0, y[6];
        std::memcpy(y, model->y0, sizeof(double) * n);
        for (size_t i = 0; i < times.size(); i++) {
            if (times[i] > t) {
                int status = gsl_odeiv2_driver_apply(d, &t, times[i], y);
                if (status != GSL_SUCCESS) {
                    gsl_odeiv2_driver_free(d);
                    return status;
                }
            }
            std::memcpy(&out[i * n], y, sizeof(double) * n);
        }
        gsl_odeiv2_driver_free(d);
        return 0;
    }
    namespace odeint = boost::numeric::odeint;
    state x(model->y0, model->y0 + n);
    std::vector<double> ts(times);
    size_t row = 0;
    auto observer = [&](const state& s, double) {
        std::memcpy(&out[row * n], s.data(), sizeof(double) * n);
        row++;
    };
    if (std::strcmp(stepper, "rkf78") == 0) {
        auto st = odeint::make_controlled(atol, rtol, odeint::runge_kutta_fehlberg78<state>());
        odeint::integrate_times(st, OdeintRhs(), x, ts.begin(), ts.end(), 1e-6, observer);
    } else if (std::strcmp(stepper, "dopri5") == 0) {
        auto st = odeint::make_dense_output(atol, rtol, odeint::runge_kutta_dopri5<state>());
        odeint::integrate_times(st, OdeintRhs(), x, ts.begin(), ts.end(), 1e-6, observer);
    } else {
        return -1;
    }
    return 0;
}

int main(int argc, char** argv) {
    if (argc != 7) {
        std::fprintf(stderr, "usage: peers MODEL STEPPER RTOL ATOL SAMPLES REPEAT\n");
        return 2;
    }
    for (const Model& m : MODELS)
        if (std::strcmp(m.name, argv[1]) == 0) model = &m;
    if (!model) {
        std::fprintf(stderr, "unknown model %s\n", argv[1]);
        return 2;
    }
    const char* stepper = argv[2];
    double rtol = std::atof(argv[3]), atol = std::atof(argv[4]);
    int samples = std::atoi(argv[5]), repeat = std::atoi(argv[6]);
    std::vector<double> times = sample_times(samples), out;
    gsl_set_error_handler_off();
    if (solve(stepper, rtol, atol, times, out) != 0) {
        std::fprintf(stderr, "{\"error\":\"solve failed\"}\n");
        return 3;
    }
    long per_solve = evaluations;
    for (size_t i = 0; i < times.size(); i++) {
        std::printf("%.17g", times[i]);
        for (int j = 0; j < model->n; j++) std::printf(",%.17g", out[i * model->n + j]);
        std::printf("\n");
    }
    double fastest = 1e300;
    for (int r = 0; r < repeat; r++) {
        auto start = std::chrono::steady_clock::now();
        solve(stepper, rtol, atol, times, out);
        std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
        if (elapsed.count() < fastest) fastest = elapsed.count();
    }
    std::fprintf(stderr, "{\"wall_time_s\":%.6e,\"rhs_evaluations\":%ld}\n", fastest, per_solve);
    return 0;
}
