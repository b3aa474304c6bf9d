/* Row loops over the generated angle functions of one joint-angle model
 * (fuzzygait.markererror.angle_kernel): every row is one set of marker positions, all
 * rows share the progression frame.  Compiled with the CasADi-generated code of
 * fg_angles (positions, progression -> 3 angles, degrees) and fg_angles_gradient
 * (positions, progression, component weights -> 3 angles and the gradient of the
 * weighted sum with respect to the perturbed markers' coordinates, degrees/mm). */
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

/* angles (k, 3) of positions x (k, n_x) */
int fg_angle_rows(long k, long n_x, const double* x, const double* progression, double* angles) {
    casadi_int n_arg, n_res, n_iw, n_w;
    workspace space;
    fg_angles_work(&n_arg, &n_res, &n_iw, &n_w);
    if (reserve(&space, n_arg, n_res, n_iw, n_w)) { release(&space); return 1; }
    for (long i = 0; i < k; ++i) {
        space.arg[0] = x + i * n_x;
        space.arg[1] = progression;
        space.res[0] = angles + 3 * i;
        fg_angles(space.arg, space.res, space.iw, space.w, 0);
    }
    release(&space);
    return 0;
}

/* angles (k, 3) and gradients (k, n_p) of weights[i] . angles[i] */
int fg_angle_gradient_rows(long k, long n_x, long n_p, const double* x, const double* progression,
                           const double* weights, double* angles, double* gradients) {
    casadi_int n_arg, n_res, n_iw, n_w;
    workspace space;
    fg_angles_gradient_work(&n_arg, &n_res, &n_iw, &n_w);
    if (reserve(&space, n_arg, n_res, n_iw, n_w)) { release(&space); return 1; }
    for (long i = 0; i < k; ++i) {
        space.arg[0] = x + i * n_x;
        space.arg[1] = progression;
        space.arg[2] = weights + 3 * i;
        space.res[0] = angles + 3 * i;
        space.res[1] = gradients + n_p * i;
        fg_angles_gradient(space.arg, space.res, space.iw, space.w, 0);
    }
    release(&space);
    return 0;
}
