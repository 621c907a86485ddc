/* A tiny C solver run by contactbench's `command` solver (docs/INTERFACES.md "The command
 * protocol"): projected gradient with Nesterov momentum and restart for
 *     minimize 1/2 x'Ax - b'x  subject to  Jx >= c,  rows of J sharing no column,
 * reading the problem as the Matrix Market folder {mtx} and writing {out}/x.txt and
 * {out}/result.json. C99 and libm only:
 *
 *     cc -O2 -o pgd_solver examples/pgd_solver.c -lm
 *     suite: "argv": ["./pgd_solver", "{mtx}", "{out}", "{tol}", "{max_iterations}"],
 *            "accepts": "decoupled"
 *
 * Step 1/L with L = max row sum of |A| (>= the largest eigenvalue: always a safe step). Its stop
 * test is stationarity |D^-1 (Ax - b - J'lambda)|_inf and penetration as fractions of the scene
 * size (the extent of x0), lambda from the rows on their face; contactbench re-judges the answer
 * with its full measure on the original QP. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct { /* a matrix as its entries (coordinate form); products loop over them */
    long rows, cols, nnz;
    long *r, *c;
    double* v;
} Coo;

static void die(const char* what, const char* path)
{
    fprintf(stderr, "pgd_solver: %s: %s\n", path, what);
    exit(2);
}

/* Opens a .mtx file, skips the banner and comments, reads the size line. */
static FILE* open_mtx(const char* dir, const char* name, long* rows, long* cols, long* nnz, int* coordinate)
{
    static char path[4096], line[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE* f = fopen(path, "r");
    if (!f) die("cannot open", path);
    if (!fgets(line, sizeof line, f) || strncmp(line, "%%MatrixMarket", 14)) die("not a Matrix Market file", path);
    *coordinate = strstr(line, "coordinate") != NULL;
    do {
        if (!fgets(line, sizeof line, f)) die("no size line", path);
    } while (line[0] == '%');
    *nnz = 0;
    if (sscanf(line, *coordinate ? "%ld %ld %ld" : "%ld %ld", rows, cols, nnz) < 2) die("bad size line", path);
    return f;
}

static Coo read_matrix(const char* dir, const char* name)
{
    Coo m;
    int coordinate;
    FILE* f = open_mtx(dir, name, &m.rows, &m.cols, &m.nnz, &coordinate);
    if (!coordinate) die("expected a coordinate matrix", name);
    m.r = malloc(sizeof(long) * (size_t)(m.nnz + 1));
    m.c = malloc(sizeof(long) * (size_t)(m.nnz + 1));
    m.v = malloc(sizeof(double) * (size_t)(m.nnz + 1));
    for (long k = 0; k < m.nnz; ++k) {
        if (fscanf(f, "%ld %ld %lf", &m.r[k], &m.c[k], &m.v[k]) != 3) die("short entry list", name);
        m.r[k]--, m.c[k]--;
    }
    fclose(f);
    return m;
}

static double* read_vector(const char* dir, const char* name, long expected)
{
    long rows, cols, nnz;
    int coordinate;
    FILE* f = open_mtx(dir, name, &rows, &cols, &nnz, &coordinate);
    if (coordinate || cols != 1 || rows != expected) die("expected an array vector of the right size", name);
    double* v = malloc(sizeof(double) * (size_t)(rows + 1));
    for (long i = 0; i < rows; ++i)
        if (fscanf(f, "%lf", &v[i]) != 1) die("short vector", name);
    fclose(f);
    return v;
}

/* y = M x (or M' x when transpose). */
static void multiply(const Coo* M, const double* x, double* y, int transpose)
{
    memset(y, 0, sizeof(double) * (size_t)(transpose ? M->cols : M->rows));
    for (long k = 0; k < M->nnz; ++k) {
        if (transpose)
            y[M->c[k]] += M->v[k] * x[M->r[k]];
        else
            y[M->r[k]] += M->v[k] * x[M->c[k]];
    }
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char** argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: pgd_solver MTX_DIR OUT_DIR TOL MAX_ITERATIONS\n");
        return 2;
    }
    const double start = now();
    const char *dir = argv[1], *out = argv[2];
    const double tol = atof(argv[3]);
    const long max_it = atol(argv[4]);
    Coo A = read_matrix(dir, "A.mtx"), J = read_matrix(dir, "J.mtx");
    const long n = A.rows, m = J.rows;
    double *b = read_vector(dir, "b.mtx", n), *c = read_vector(dir, "c.mtx", m), *x0 = read_vector(dir, "x0.mtx", n);

    double *diag = calloc((size_t)n + 1, sizeof(double)), *rowsum = calloc((size_t)n + 1, sizeof(double));
    double* norm2 = calloc((size_t)m + 1, sizeof(double));
    for (long k = 0; k < A.nnz; ++k) {
        rowsum[A.r[k]] += fabs(A.v[k]);
        if (A.r[k] == A.c[k]) diag[A.r[k]] = A.v[k];
    }
    for (long k = 0; k < J.nnz; ++k) norm2[J.r[k]] += J.v[k] * J.v[k];
    double L = 0.0;
    for (long i = 0; i < n; ++i) L = rowsum[i] > L ? rowsum[i] : L;
    double length = 0.0; /* scene size: largest axis extent of x0 as 3-D points */
    for (int axis = 0; axis < 3 && n % 3 == 0; ++axis) {
        double lo = INFINITY, hi = -INFINITY;
        for (long i = axis; i < n; i += 3) lo = x0[i] < lo ? x0[i] : lo, hi = x0[i] > hi ? x0[i] : hi;
        length = hi - lo > length ? hi - lo : length;
    }
    if (!(length > 0)) length = 1.0;

    double *x = malloc(sizeof(double) * (size_t)n), *x_prev = malloc(sizeof(double) * (size_t)n);
    double *y = malloc(sizeof(double) * (size_t)n), *g = malloc(sizeof(double) * (size_t)n);
    double *Jx = malloc(sizeof(double) * (size_t)m + 8), *w = malloc(sizeof(double) * (size_t)m + 8);
    double *lambda = calloc((size_t)m + 1, sizeof(double)), *r = malloc(sizeof(double) * (size_t)n);

/* x += J' max(0, c - Jx) / |J_i|^2: exact projection when rows share no column. */
#define PROJECT(v)                                                                                                     \
    do {                                                                                                               \
        multiply(&J, v, Jx, 0);                                                                                        \
        for (long i = 0; i < m; ++i) w[i] = norm2[i] > 0 && c[i] > Jx[i] ? (c[i] - Jx[i]) / norm2[i] : 0.0;            \
        multiply(&J, w, r, 1);                                                                                         \
        for (long j = 0; j < n; ++j) v[j] += r[j];                                                                     \
    } while (0)

    memcpy(x, x0, sizeof(double) * (size_t)n);
    PROJECT(x);
    memcpy(x_prev, x, sizeof(double) * (size_t)n);
    memcpy(y, x, sizeof(double) * (size_t)n);
    double t = 1.0, f_prev = INFINITY, error = INFINITY;
    const double setup_end = now();
    long it = 0;
    const char* status = "max_iterations";
    while (it < max_it) {
        ++it;
        multiply(&A, y, g, 0);
        for (long j = 0; j < n; ++j) x[j] = y[j] - (g[j] - b[j]) / L;
        PROJECT(x);
        multiply(&A, x, g, 0); /* g = Ax - b from here on */
        double f = 0.0;
        for (long j = 0; j < n; ++j) g[j] -= b[j], f += 0.5 * x[j] * (g[j] - b[j]);
        const double t_next = f > f_prev ? 1.0 : 0.5 * (1.0 + sqrt(1.0 + 4.0 * t * t));
        const double beta = f > f_prev ? 0.0 : (t - 1.0) / t_next; /* restart on an increase */
        for (long j = 0; j < n; ++j) y[j] = x[j] + beta * (x[j] - x_prev[j]), x_prev[j] = x[j];
        t = t_next, f_prev = f;
        /* stop test: lambda on the rows on their face, then stationarity and penetration */
        multiply(&J, x, Jx, 0);
        multiply(&J, g, w, 0);
        double primal = 0.0;
        for (long i = 0; i < m; ++i) {
            const double gap = norm2[i] > 0 ? (Jx[i] - c[i]) / sqrt(norm2[i]) : 0.0;
            lambda[i] = norm2[i] > 0 && gap <= 1e-12 * length && w[i] > 0 ? w[i] / norm2[i] : 0.0;
            primal = -gap > primal ? -gap : primal;
        }
        multiply(&J, lambda, r, 1);
        double stationarity = 0.0;
        for (long j = 0; j < n; ++j) {
            const double s = fabs((g[j] - r[j]) / diag[j]);
            stationarity = s > stationarity ? s : stationarity;
        }
        error = (stationarity > primal ? stationarity : primal) / length;
        /* A hundredth of tol: this test leaves out the measure's rigid motion of each body
           (docs/accuracy.md), which a stiff body's residual can hide from the Jacobi step. */
        if (error <= 0.01 * tol) {
            status = "converged";
            break;
        }
    }
    const double end = now();

    char path[4096];
    snprintf(path, sizeof path, "%s/x.txt", out);
    FILE* f = fopen(path, "w");
    if (!f) die("cannot write", path);
    for (long j = 0; j < n; ++j) fprintf(f, "%.17g\n", x[j]);
    fclose(f);
    snprintf(path, sizeof path, "%s/lambda.txt", out);
    if (!(f = fopen(path, "w"))) die("cannot write", path);
    for (long i = 0; i < m; ++i) fprintf(f, "%.17g\n", lambda[i]);
    fclose(f);
    snprintf(path, sizeof path, "%s/result.json", out);
    if (!(f = fopen(path, "w"))) die("cannot write", path);
    fprintf(f, "{\"status\": \"%s\", \"iterations\": %ld, \"setup_s\": %.9f, \"solve_s\": %.9f, \"residual\": %.17g}\n",
            status, it, setup_end - start, end - setup_end, error);
    fclose(f);
    return 0;
}
