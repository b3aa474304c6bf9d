/* Row loops over the generated angle functions of one joint-angle model
 * (fuzzygait.markererror.angle_kernel): every row is one set of marker positions, all
 * rows share the progression frame.  Compiled with the CasADi-generated code of
 * fg_angles (positions, progression -> 3 angles, degrees) and fg_angles_gradient
 * (positions, progression, component weights -> 3 angles and the gradient of the
 * weighted sum with respect to the perturbed markers' coordinates, degrees/mm). */
#include <math.h>
#include <stdlib.h>

typedef long long int casadi_int;

int fg_angles(const double** arg, double** res, casadi_int* iw, double* w, int mem);
int fg_angles_work(casadi_int* sz_arg, casadi_int* sz_res, casadi_int* sz_iw, casadi_int* sz_w);
int fg_angles_gradient(const double** arg, double** res, casadi_int* iw, double* w, int mem);
int fg_angles_gradient_work(casadi_int* sz_arg, casadi_int* sz_res, casadi_int* sz_iw, casadi_int* sz_w);

typedef struct {
    const double** arg;
    double** res;
    casadi_int* iw;
    double* w;
} workspace;

static int reserve(workspace* space, casadi_int n_arg, casadi_int n_res, casadi_int n_iw, casadi_int n_w) {
    space->arg = malloc(sizeof(double*) * (size_t)(n_arg > 0 ? n_arg : 1));
    space->res = malloc(sizeof(double*) * (size_t)(n_res > 0 ? n_res : 1));
    space->iw = malloc(sizeof(casadi_int) * (size_t)(n_iw > 0 ? n_iw : 1));
    space->w = malloc(sizeof(double) * (size_t)(n_w > 0 ? n_w : 1));
    return space->arg && space->res && space->iw && space->w ? 0 : 1;
}

static void release(workspace* space) {
    free(space->arg);
    free(space->res);
    free(space->iw);
    free(space->w);
}

/* Row i's positions: the base positions of its frame, nodes[i], (n_frames, n_x; the
 * perturbed markers' coordinates first, then the fixed markers') plus its deviations P[i]
 * (n_p) on the first n_p coordinates.  Returns 0 (all finite) or 1 (a position missing). */
static int positions(long i, long n_x, long n_p, const double* base, const long* nodes, const double* P,
                     double* x) {
    const double* b = base + nodes[i] * n_x;
    const double* p = P + i * n_p;
    int missing = 0;
    for (long j = 0; j < n_x; ++j) {
        x[j] = b[j] + (j < n_p ? p[j] : 0.0);
        if (!(x[j] - x[j] == 0.0)) missing = 1; /* NaN or infinite */
    }
    return missing;
}

/* status per row: 0 the angles, 1 a position missing (angles and gradients NaN), 2 the
 * angles came out NaN from measured positions (the caller asks the chain). */
static void settle(long i, int missing, double* angles, double* gradients, long n_p, signed char* status) {
    int defined = angles[3 * i] == angles[3 * i] && angles[3 * i + 1] == angles[3 * i + 1]
                  && angles[3 * i + 2] == angles[3 * i + 2];
    status[i] = missing ? 1 : (defined ? 0 : 2);
    if (missing) {
        for (int c = 0; c < 3; ++c) angles[3 * i + c] = NAN;
        if (gradients) for (long j = 0; j < n_p; ++j) gradients[i * n_p + j] = NAN;
    }
}

/* angles (k, 3) */
int fg_angle_rows(long k, long n_x, long n_p, const double* base, const long* nodes, const double* P,
                  const double* progression, double* angles, signed char* status) {
    casadi_int n_arg, n_res, n_iw, n_w;
    workspace space;
    double* x = malloc(sizeof(double) * (size_t)(n_x > 0 ? n_x : 1));
    fg_angles_work(&n_arg, &n_res, &n_iw, &n_w);
    if (!x || reserve(&space, n_arg, n_res, n_iw, n_w)) { free(x); release(&space); return 1; }
    for (long i = 0; i < k; ++i) {
        int missing = positions(i, n_x, n_p, base, nodes, P, x);
        space.arg[0] = x;
        space.arg[1] = progression;
        space.res[0] = angles + 3 * i;
        fg_angles(space.arg, space.res, space.iw, space.w, 0);
        settle(i, missing, angles, 0, n_p, status);
    }
    free(x);
    release(&space);
    return 0;
}

/* angles (k, 3) and gradients (k, n_p) of component axes[i] of row i */
int fg_angle_gradient_rows(long k, long n_x, long n_p, const double* base, const long* nodes, const double* P,
                           const double* progression, const long* axes, double* angles, double* gradients,
                           signed char* status) {
    casadi_int n_arg, n_res, n_iw, n_w;
    workspace space;
    double* x = malloc(sizeof(double) * (size_t)(n_x > 0 ? n_x : 1));
    double weights[3];
    fg_angles_gradient_work(&n_arg, &n_res, &n_iw, &n_w);
    if (!x || reserve(&space, n_arg, n_res, n_iw, n_w)) { free(x); release(&space); return 1; }
    for (long i = 0; i < k; ++i) {
        int missing = positions(i, n_x, n_p, base, nodes, P, x);
        for (int c = 0; c < 3; ++c) weights[c] = c == axes[i] ? 1.0 : 0.0;
        space.arg[0] = x;
        space.arg[1] = progression;
        space.arg[2] = weights;
        space.res[0] = angles + 3 * i;
        space.res[1] = gradients + n_p * i;
        fg_angles_gradient(space.arg, space.res, space.iw, space.w, 0);
        settle(i, missing, angles, gradients, n_p, status);
    }
    free(x);
    release(&space);
    return 0;
}
