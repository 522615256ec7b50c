// The compiled peers of scripts/bench_vs_gsl.py: GSL's rk8pd (Prince-Dormand
// 8(7), gsl_odeiv2 driver) and Boost odeint's runge_kutta_fehlberg78
// (controlled) and runge_kutta_dopri5 (dense output) on the reduced systems
// (7) of four lagc models, written here by hand from `lagc derive` / the
// generated crate's `rhs` (same operations, same number of sin/cos/tan
// calls; parameters are compile-time constants).
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
    double e_7 = 1.0 / (c * c);
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
// Unit masses and links: sum_j c_ij [cos(th_i - th_j) th_j'' + sin(th_i -
// th_j) th_j'^2] + g c_ii sin(th_i) = 0, c_ij = 3 - max(i, j); six trig
// calls (the generated crate's count), the 3x3 mass matrix solved by
// Gaussian elimination with partial pivoting (as lagc's solve_fixed).
static void pendulum_3(double, const double* x, double* dx) {
    const int N = 3;
    const double g = 9.81;
    double s[N], c[N], a[N][N], b[N];
    for (int i = 0; i < N; i++) {
        s[i] = std::sin(x[i]);
        c[i] = std::cos(x[i]);
    }
    for (int i = 0; i < N; i++) {
        b[i] = -g * (N - i) * s[i];
        for (int j = 0; j < N; j++) {
            double cij = N - (i > j ? i : j);
            a[i][j] = cij * (c[i] * c[j] + s[i] * s[j]);
            b[i] -= cij * (s[i] * c[j] - c[i] * s[j]) * x[N + j] * x[N + j];
        }
    }
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
    for (int i = 0; i < N; i++) {
        dx[i] = x[N + i];
        dx[N + i] = b[i];
    }
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
