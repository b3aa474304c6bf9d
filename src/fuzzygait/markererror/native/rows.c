/* Row loops over the generated functions of one compiled model
 * (fuzzygait.markererror.row_kernel).  Row i is the function of
 *   x = base[nodes[i]] (n_x: what the row's frame gives: marker positions, loads),
 *   p = P[i]           (n_p: the row's deviations, the parameters),
 *   q                  (n_q: shared by every row: the progression frame, constants);
 * fg_values gives its outputs (n_out selectable ones, then n_checks checks); fg_gradient(x, p,
 * q, w) the outputs and the gradient with respect to p of w . (selectable outputs), w the
 * indicator of the output selected by select[i]. */
#include <math.h>
#include <stdlib.h>

typedef long long int casadi_int;

int fg_values(const double** arg, double** res, casadi_int* iw, double* w, int mem);
int fg_values_work(casadi_int* sz_arg, casadi_int* sz_res, casadi_int* sz_iw, casadi_int* sz_w);
int fg_gradient(const double** arg, double** res, casadi_int* iw, double* w, int mem);
int fg_gradient_work(casadi_int* sz_arg, casadi_int* sz_res, casadi_int* sz_iw, casadi_int* sz_w);

typedef struct {
    const double** arg;
    double** res;
    casadi_int* iw;
    double* w;
    double* weights; /* n_out */
    double* row;     /* n_out + n_checks */
} workspace;

static void release(workspace* space) {
    free(space->arg);
    free(space->res);
    free(space->iw);
    free(space->w);
    free(space->weights);
    free(space->row);
}

static int reserve(workspace* space, int (*work)(casadi_int*, casadi_int*, casadi_int*, casadi_int*), long n_values) {
    casadi_int n_arg, n_res, n_iw, n_w;
    work(&n_arg, &n_res, &n_iw, &n_w);
    space->arg = malloc(sizeof(double*) * (size_t)(n_arg > 0 ? n_arg : 1));
    space->res = malloc(sizeof(double*) * (size_t)(n_res > 0 ? n_res : 1));
    space->iw = malloc(sizeof(casadi_int) * (size_t)(n_iw > 0 ? n_iw : 1));
    space->w = malloc(sizeof(double) * (size_t)(n_w > 0 ? n_w : 1));
    space->weights = malloc(sizeof(double) * (size_t)(n_values > 0 ? n_values : 1));
    space->row = malloc(sizeof(double) * (size_t)(n_values > 0 ? n_values : 1));
    if (space->arg && space->res && space->iw && space->w && space->weights && space->row) return 0;
    release(space);
    return 1;
}

static int all_finite(const double* v, long n) {
    for (long j = 0; j < n; ++j)
        if (!(v[j] - v[j] == 0.0)) return 0; /* NaN or infinite */
    return 1;
}

/* status: 0 outputs, 1 an input missing (outputs and gradients NaN), 2 outputs NaN from
 * measured inputs (the caller computes those rows another way) */
static signed char row_status(int measured, const double* out, long n_out) {
    return measured ? (all_finite(out, n_out) ? 0 : 2) : 1;
}

static void fill_nan(double* v, long n) {
    for (long j = 0; j < n; ++j) v[j] = NAN;
}

int fg_value_rows(long k, long n_x, long n_p, long n_out, const double* base, const long* nodes, const double* P,
                  const double* q, double* out, signed char* status) {
    workspace space;
    if (reserve(&space, fg_values_work, n_out)) return 1;
    for (long i = 0; i < k; ++i) {
        const double* x = base + nodes[i] * n_x;
        const double* p = P + i * n_p;
        space.arg[0] = x;
        space.arg[1] = p;
        space.arg[2] = q;
        space.res[0] = out + i * n_out;
        fg_values(space.arg, space.res, space.iw, space.w, 0);
        status[i] = row_status(all_finite(x, n_x) && all_finite(p, n_p), out + i * n_out, n_out);
        if (status[i] == 1) fill_nan(out + i * n_out, n_out);
    }
    release(&space);
    return 0;
}

/* per row: the selected output, the checks and the selected output's gradient */
int fg_gradient_rows(long k, long n_x, long n_p, long n_out, long n_checks, const double* base, const long* nodes,
                     const double* P, const double* q, const long* select, double* values, double* checks,
                     double* gradients, signed char* status) {
    workspace space;
    if (reserve(&space, fg_gradient_work, n_out + n_checks)) return 1;
    for (long i = 0; i < k; ++i) {
        const double* x = base + nodes[i] * n_x;
        const double* p = P + i * n_p;
        for (long c = 0; c < n_out; ++c) space.weights[c] = c == select[i] ? 1.0 : 0.0;
        space.arg[0] = x;
        space.arg[1] = p;
        space.arg[2] = q;
        space.arg[3] = space.weights;
        space.res[0] = space.row;
        space.res[1] = gradients + i * n_p;
        fg_gradient(space.arg, space.res, space.iw, space.w, 0);
        values[i] = space.row[select[i]];
        for (long c = 0; c < n_checks; ++c) checks[i * n_checks + c] = space.row[n_out + c];
        status[i] = row_status(all_finite(x, n_x) && all_finite(p, n_p), space.row, n_out + n_checks);
        if (status[i] == 1) {
            values[i] = NAN;
            fill_nan(checks + i * n_checks, n_checks);
            fill_nan(gradients + i * n_p, n_p);
        }
    }
    release(&space);
    return 0;
}
