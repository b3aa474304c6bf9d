/* The time-stepping loop of fuzzygait's simulator in C (mechanics/native.py loads it).
 *
 * It solves every step of the variational or energy-momentum scheme with the same modified
 * Newton iteration as mechanics/integrator.py (kept factorisation, refreshed when an update
 * shrinks by less than REFRESH_CONTRACTION, a stray chord step undone, updates capped at
 * MAX_UPDATE, the same convergence test), the same folding check and the same sensitivity
 * recursion, calling the CasADi-generated step functions fgs_{res,jac,sens}_{vi1,vi,em}
 * (mechanics/step_functions.py) compiled into the same library.
 *
 * Linear algebra: a sparse LU with a fixed pivot order.  The caller gives the row and
 * column permutations of a pivoting factorisation of one Jacobian (SuperLU's perm_r /
 * perm_c); the fill pattern of L and U for that order is computed once and every later
 * Jacobian is factorised into it (left-looking, no search for pivots).  When a pivot falls
 * below PIVOT_RATIO of the largest candidate of its eliminated column (the test of
 * threshold partial pivoting) the run returns FG_PIVOT, the caller supplies a fresh
 * order for the Jacobian at that point (fg_jacobian) and the run resumes there with it.
 * The sensitivities' LU has its own order, so the Newton path does not depend on them.
 *
 * Layouts: q (n_steps + 1, n), multipliers (n_steps, m), velocities (n_steps + 1, n) and
 * sensitivities (n_steps + 1, n, n_p) are row-major numpy arrays owned by the caller.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fgs_gen.h"

#define REFRESH_CONTRACTION 0.25
#define MAX_UPDATE 0.2
#define FOLD_COSINE 0.0
#define PIVOT_RATIO 1e-2

enum { FG_OK = 0, FG_NEWTON = 1, FG_FOLD = 2, FG_PIVOT = 3, FG_MEMORY = 4 };

typedef int (*casadi_fn)(const casadi_real **, casadi_real **, casadi_int *, casadi_real *, int);
typedef int (*casadi_work_fn)(casadi_int *, casadi_int *, casadi_int *, casadi_int *);

typedef struct {
  casadi_fn f;
  const casadi_real **arg;
  casadi_real **res;
  casadi_int *iw;
  casadi_real *w;
} fn_t;

static int fn_init(fn_t *fn, casadi_fn f, casadi_work_fn work) {
  casadi_int sz_arg, sz_res, sz_iw, sz_w;
  work(&sz_arg, &sz_res, &sz_iw, &sz_w);
  fn->f = f;
  fn->arg = calloc(sz_arg > 0 ? sz_arg : 1, sizeof(casadi_real *));
  fn->res = calloc(sz_res > 0 ? sz_res : 1, sizeof(casadi_real *));
  fn->iw = calloc(sz_iw > 0 ? sz_iw : 1, sizeof(casadi_int));
  fn->w = calloc(sz_w > 0 ? sz_w : 1, sizeof(casadi_real));
  return fn->arg && fn->res && fn->iw && fn->w;
}

static void fn_free(fn_t *fn) {
  free(fn->arg); free(fn->res); free(fn->iw); free(fn->w);
}

/* ---- sparse LU with a fixed pivot order ------------------------------------------------ */
typedef struct {
  int N;
  int *bp, *bi, *bmap;   /* permuted matrix B = Pr A Pc by columns: rows and A-nonzero index */
  int *lp, *li, *up, *ui; /* patterns of L (strictly lower) and U (upper incl. diagonal last) */
  int *perm_r, *perm_c;   /* old row -> new row, old column -> new column */
  int analysed;
} lu_symbolic_t;

typedef struct {
  double *lx, *ux;
  int valid;
} lu_numeric_t;

static void lu_symbolic_free(lu_symbolic_t *s) {
  free(s->bp); free(s->bi); free(s->bmap); free(s->lp); free(s->li); free(s->up); free(s->ui);
  free(s->perm_r); free(s->perm_c);
  memset(s, 0, sizeof(*s));
}

/* Patterns of B and of its L and U factors for the order (perm_r, perm_c). */
static int lu_analyse(lu_symbolic_t *s, int N, const int *ap, const int *ai, const int *perm_r,
                      const int *perm_c) {
  lu_symbolic_t t;
  memset(&t, 0, sizeof(t));
  t.N = N;
  int nnz = ap[N];
  t.perm_r = malloc(N * sizeof(int));
  t.perm_c = malloc(N * sizeof(int));
  t.bp = calloc(N + 1, sizeof(int));
  t.bi = malloc((nnz > 0 ? nnz : 1) * sizeof(int));
  t.bmap = malloc((nnz > 0 ? nnz : 1) * sizeof(int));
  int *mark = calloc(N, sizeof(int));
  int *inverse_c = malloc(N * sizeof(int));
  if (!t.perm_r || !t.perm_c || !t.bp || !t.bi || !t.bmap || !mark || !inverse_c) goto fail;
  memcpy(t.perm_r, perm_r, N * sizeof(int));
  memcpy(t.perm_c, perm_c, N * sizeof(int));
  for (int j = 0; j < N; ++j) inverse_c[perm_c[j]] = j;
  for (int jn = 0; jn < N; ++jn) {
    int jo = inverse_c[jn];
    t.bp[jn + 1] = t.bp[jn] + (ap[jo + 1] - ap[jo]);
    int out = t.bp[jn];
    for (int k = ap[jo]; k < ap[jo + 1]; ++k, ++out) {
      t.bi[out] = perm_r[ai[k]];
      t.bmap[out] = k;
    }
  }
  /* symbolic left-looking factorisation: column j of L U = reach of B[:, j] over L */
  int cap_l = 4 * nnz + N, cap_u = 4 * nnz + N, nl = 0, nu = 0;
  t.lp = calloc(N + 1, sizeof(int));
  t.up = calloc(N + 1, sizeof(int));
  t.li = malloc(cap_l * sizeof(int));
  t.ui = malloc(cap_u * sizeof(int));
  if (!t.lp || !t.up || !t.li || !t.ui) goto fail;
  for (int j = 0; j < N; ++j) {
    for (int k = t.bp[j]; k < t.bp[j + 1]; ++k) mark[t.bi[k]] = j + 1;
    for (int k = 0; k < j; ++k) {
      if (mark[k] != j + 1) continue;
      for (int r = t.lp[k]; r < t.lp[k + 1]; ++r) mark[t.li[r]] = j + 1;
    }
    if (mark[j] != j + 1) goto fail; /* structurally zero pivot: not a valid order */
    for (int i = 0; i < N; ++i) {
      if (mark[i] != j + 1) continue;
      if (i <= j) {
        if (nu >= cap_u) { cap_u *= 2; int *p = realloc(t.ui, cap_u * sizeof(int)); if (!p) goto fail; t.ui = p; }
        t.ui[nu++] = i;
      } else {
        if (nl >= cap_l) { cap_l *= 2; int *p = realloc(t.li, cap_l * sizeof(int)); if (!p) goto fail; t.li = p; }
        t.li[nl++] = i;
      }
    }
    t.lp[j + 1] = nl;
    t.up[j + 1] = nu;
  }
  free(mark); free(inverse_c);
  lu_symbolic_free(s);
  *s = t;
  s->analysed = 1;
  return 1;
fail:
  free(mark); free(inverse_c);
  lu_symbolic_free(&t);
  return 0;
}

static int lu_numeric_alloc(lu_numeric_t *f, const lu_symbolic_t *s) {
  free(f->lx); free(f->ux);
  f->lx = malloc((s->lp[s->N] > 0 ? s->lp[s->N] : 1) * sizeof(double));
  f->ux = malloc((s->up[s->N] > 0 ? s->up[s->N] : 1) * sizeof(double));
  f->valid = 0;
  return f->lx && f->ux;
}

/* Factorise A (nonzeros ax in the analysed pattern).  Returns 1, or 0 when a pivot is too
 * small for this order (or not finite); work: N doubles. */
static int lu_factorise(const lu_symbolic_t *s, lu_numeric_t *f, const double *ax, double *work) {
  int N = s->N;
  f->valid = 0;
  for (int j = 0; j < N; ++j) {
    for (int k = s->up[j]; k < s->up[j + 1]; ++k) work[s->ui[k]] = 0.0;
    for (int k = s->lp[j]; k < s->lp[j + 1]; ++k) work[s->li[k]] = 0.0;
    for (int k = s->bp[j]; k < s->bp[j + 1]; ++k) work[s->bi[k]] += ax[s->bmap[k]];
    for (int k = s->up[j]; k < s->up[j + 1] - 1; ++k) { /* ascending rows < j */
      int r = s->ui[k];
      double xr = work[r];
      if (xr == 0.0) continue;
      for (int l = s->lp[r]; l < s->lp[r + 1]; ++l) work[s->li[l]] -= f->lx[l] * xr;
    }
    double pivot = work[j], candidates = 0.0; /* the largest entry pivoting could have chosen instead */
    for (int k = s->lp[j]; k < s->lp[j + 1]; ++k) if (fabs(work[s->li[k]]) > candidates) candidates = fabs(work[s->li[k]]);
    if (!isfinite(pivot) || !isfinite(candidates) || pivot == 0.0 || fabs(pivot) < PIVOT_RATIO * candidates) return 0;
    for (int k = s->up[j]; k < s->up[j + 1]; ++k) f->ux[k] = work[s->ui[k]];
    double inverse = 1.0 / pivot;
    for (int k = s->lp[j]; k < s->lp[j + 1]; ++k) f->lx[k] = work[s->li[k]] * inverse;
  }
  f->valid = 1;
  return 1;
}

/* Solve A z = b in place (b -> z); work: N doubles. */
static void lu_solve(const lu_symbolic_t *s, const lu_numeric_t *f, double *b, double *work) {
  int N = s->N;
  for (int i = 0; i < N; ++i) work[s->perm_r[i]] = b[i];
  for (int j = 0; j < N; ++j) {
    double xj = work[j];
    if (xj == 0.0) continue;
    for (int l = s->lp[j]; l < s->lp[j + 1]; ++l) work[s->li[l]] -= f->lx[l] * xj;
  }
  for (int j = N - 1; j >= 0; --j) {
    int diagonal = s->up[j + 1] - 1;
    double xj = work[j] / f->ux[diagonal];
    work[j] = xj;
    if (xj == 0.0) continue;
    for (int k = s->up[j]; k < diagonal; ++k) work[s->ui[k]] -= f->ux[k] * xj;
  }
  for (int i = 0; i < N; ++i) b[i] = work[s->perm_c[i]];
}

/* Newton iteration state of the step in progress (kept across FG_PIVOT returns). */
typedef struct {
  int active, need_factor, k, fresh_here, last_stale, have_last;
  double previous;
} newton_state_t;

/* ---- the integration context ------------------------------------------------------------ */
typedef struct {
  int n, m, N, n_p, n_steps, scheme, sensitivities, max_iterations;
  double h, tolerance, constraint_tolerance;
  const double *p, *c, *gc, *v0;
  double *q, *lam, *vel, *sens; /* caller's output arrays (vel, sens may be NULL) */
  int *iterations;
  /* fold check: pairs of d3 offsets, grouped */
  int n_pairs, n_fold_groups;
  const int *pair_a, *pair_b, *group_start; /* group_start: n_fold_groups + 1 */
  /* functions */
  fn_t res[3], jac[3], sens_fn[3];
  int jac_nnz;
  int *jac_p, *jac_i;
  /* state */
  int step;          /* next step to take */
  int have_lu;
  newton_state_t newton_state;
  int sens_pending; /* step `step` converged; its sensitivities wait for a new exact-LU order */
  int pivot_which;  /* after FG_PIVOT: 0 the Newton LU, 1 the exact LU of the sensitivities */
  lu_symbolic_t symbolic[2]; /* pivot orders: Newton's, and the sensitivities' own (so that the
                                Newton path does not depend on whether sensitivities are computed) */
  lu_numeric_t newton, exact;
  double *x, *residual, *dx, *last_dx, *jx, *work, *zeros, *sens_v, *rhs, *column, *s_zero;
  /* outcome */
  int status_step, status_iterations, status_index;
  double status_value;
  /* statistics */
  int factorisations;
  double t_evaluation, t_factorisation, t_solve, t_sensitivity;
} fg_context;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void context_free_members(fg_context *ctx) {
  for (int v = 0; v < 3; ++v) { fn_free(&ctx->res[v]); fn_free(&ctx->jac[v]); fn_free(&ctx->sens_fn[v]); }
  lu_symbolic_free(&ctx->symbolic[0]);
  lu_symbolic_free(&ctx->symbolic[1]);
  free(ctx->newton.lx); free(ctx->newton.ux); free(ctx->exact.lx); free(ctx->exact.ux);
  free(ctx->jac_p); free(ctx->jac_i);
  free(ctx->x); free(ctx->residual); free(ctx->dx); free(ctx->last_dx); free(ctx->jx); free(ctx->work);
  free(ctx->zeros); free(ctx->sens_v); free(ctx->rhs); free(ctx->column); free(ctx->s_zero);
}

void fg_free(fg_context *ctx) {
  if (!ctx) return;
  context_free_members(ctx);
  free(ctx);
}

/* variant index: 0 vi1, 1 vi, 2 em */
static int variant_of(const fg_context *ctx, int step) {
  if (ctx->scheme == 1) return 2;
  return step == 0 ? 0 : 1;
}

fg_context *fg_new(int n, int m, int n_p, int n_steps, int scheme, int sensitivities, double h,
                   double tolerance, double constraint_tolerance, int max_iterations,
                   const double *p, const double *c, const double *gc, const double *q0, const double *v0,
                   double *q, double *lam, double *vel, double *sens, int *iterations,
                   int n_pairs, const int *pair_a, const int *pair_b, int n_fold_groups, const int *group_start) {
  fg_context *ctx = calloc(1, sizeof(fg_context));
  if (!ctx) return NULL;
  ctx->n = n; ctx->m = m; ctx->N = n + m; ctx->n_p = n_p; ctx->n_steps = n_steps; ctx->scheme = scheme;
  ctx->sensitivities = sensitivities; ctx->h = h; ctx->tolerance = tolerance;
  ctx->constraint_tolerance = constraint_tolerance; ctx->max_iterations = max_iterations;
  ctx->p = p; ctx->c = c; ctx->gc = gc; ctx->v0 = v0;
  ctx->q = q; ctx->lam = lam; ctx->vel = vel; ctx->sens = sens; ctx->iterations = iterations;
  ctx->n_pairs = n_pairs; ctx->pair_a = pair_a; ctx->pair_b = pair_b;
  ctx->n_fold_groups = n_fold_groups; ctx->group_start = group_start;
  int ok = 1;
  ok &= fn_init(&ctx->res[0], fgs_res_vi1, fgs_res_vi1_work);
  ok &= fn_init(&ctx->res[1], fgs_res_vi, fgs_res_vi_work);
  ok &= fn_init(&ctx->res[2], fgs_res_em, fgs_res_em_work);
  ok &= fn_init(&ctx->jac[0], fgs_jac_vi1, fgs_jac_vi1_work);
  ok &= fn_init(&ctx->jac[1], fgs_jac_vi, fgs_jac_vi_work);
  ok &= fn_init(&ctx->jac[2], fgs_jac_em, fgs_jac_em_work);
  ok &= fn_init(&ctx->sens_fn[0], fgs_sens_vi1, fgs_sens_vi1_work);
  ok &= fn_init(&ctx->sens_fn[1], fgs_sens_vi, fgs_sens_vi_work);
  ok &= fn_init(&ctx->sens_fn[2], fgs_sens_em, fgs_sens_em_work);
  const casadi_int *sparsity = scheme == 1 ? fgs_jac_em_sparsity_out(0) : fgs_jac_vi_sparsity_out(0);
  int N = ctx->N;
  ctx->jac_nnz = (int)sparsity[2 + N];
  ctx->jac_p = malloc((N + 1) * sizeof(int));
  ctx->jac_i = malloc((ctx->jac_nnz > 0 ? ctx->jac_nnz : 1) * sizeof(int));
  size_t sz = (size_t)N * sizeof(double);
  ctx->x = malloc(sz); ctx->residual = malloc(sz); ctx->dx = malloc(sz); ctx->last_dx = malloc(sz);
  ctx->work = malloc(sz); ctx->column = malloc(sz);
  ctx->jx = malloc((ctx->jac_nnz > 0 ? ctx->jac_nnz : 1) * sizeof(double));
  ctx->zeros = calloc(n > 0 ? n : 1, sizeof(double));
  size_t s_sz = (size_t)(n_p > 0 ? n_p : 1) * (size_t)(N > 0 ? N : 1) * sizeof(double);
  ctx->sens_v = calloc(1, s_sz); ctx->rhs = malloc(s_sz); ctx->s_zero = calloc(1, s_sz);
  if (!ok || !ctx->jac_p || !ctx->jac_i || !ctx->x || !ctx->residual || !ctx->dx || !ctx->last_dx || !ctx->work
      || !ctx->column || !ctx->jx || !ctx->zeros || !ctx->sens_v || !ctx->rhs || !ctx->s_zero) {
    fg_free(ctx);
    return NULL;
  }
  for (int j = 0; j <= N; ++j) ctx->jac_p[j] = (int)sparsity[2 + j];
  for (int k = 0; k < ctx->jac_nnz; ++k) ctx->jac_i[k] = (int)sparsity[3 + N + k];
  memcpy(q, q0, n * sizeof(double));
  if (vel) memcpy(vel, v0, n * sizeof(double));
  if (sens) memset(sens, 0, (size_t)n * n_p * sizeof(double));
  for (int i = 0; i < n; ++i) ctx->x[i] = q0[i] + h * v0[i];
  for (int i = n; i < N; ++i) ctx->x[i] = 0.0;
  return ctx;
}

int fg_jacobian_nnz(const fg_context *ctx) { return ctx->jac_nnz; }

void fg_jacobian_pattern(const fg_context *ctx, int *indptr, int *indices) {
  memcpy(indptr, ctx->jac_p, (ctx->N + 1) * sizeof(int));
  memcpy(indices, ctx->jac_i, ctx->jac_nnz * sizeof(int));
}

/* the step's known inputs */
static void step_inputs(fg_context *ctx, int step, const double **args, const double *x) {
  int n = ctx->n;
  const double *q_cur = ctx->q + (size_t)step * n;
  const double *q_prev = step > 0 ? ctx->q + (size_t)(step - 1) * n : ctx->q;
  const double *v = ctx->v0;
  if (ctx->scheme == 1 && ctx->vel) v = ctx->vel + (size_t)step * n;
  args[0] = x; args[1] = q_cur; args[2] = q_prev; args[3] = v;
  args[4] = ctx->p; args[5] = ctx->c; args[6] = ctx->gc; args[7] = &ctx->h;
}

static void evaluate(fg_context *ctx, fn_t *fn, int step, const double *x, double *out) {
  step_inputs(ctx, step, fn->arg, x);
  fn->res[0] = out;
  fn->f(fn->arg, fn->res, fn->iw, fn->w, 0);
}

/* Jacobian of the step `step` at the context's current x (nonzeros in fg_jacobian_pattern order). */
void fg_jacobian(fg_context *ctx, double *out) {
  evaluate(ctx, &ctx->jac[variant_of(ctx, ctx->step)], ctx->step, ctx->x, out);
}

/* A new pivot order for the Newton LU (which 0) or the sensitivities' exact LU (which 1). */
int fg_set_pivots(fg_context *ctx, int which, const int *perm_r, const int *perm_c) {
  lu_symbolic_t *symbolic = &ctx->symbolic[which];
  lu_numeric_t *numeric = which == 0 ? &ctx->newton : &ctx->exact;
  if (!lu_analyse(symbolic, ctx->N, ctx->jac_p, ctx->jac_i, perm_r, perm_c)) return 0;
  if (!lu_numeric_alloc(numeric, symbolic)) return 0;
  if (which == 0) ctx->have_lu = 0;
  return 1;
}

int fg_pivot_which(const fg_context *ctx) { return ctx->pivot_which; }

int fg_factor_size(const fg_context *ctx) {
  return ctx->symbolic[0].analysed ? ctx->symbolic[0].lp[ctx->N] + ctx->symbolic[0].up[ctx->N] : 0;
}

static int factorise(fg_context *ctx, lu_numeric_t *f, int step, const double *x) {
  const lu_symbolic_t *symbolic = &ctx->symbolic[f == &ctx->exact];
  double t0 = now();
  evaluate(ctx, &ctx->jac[variant_of(ctx, step)], step, x, ctx->jx);
  double t1 = now();
  ctx->t_evaluation += t1 - t0;
  int ok = lu_factorise(symbolic, f, ctx->jx, ctx->work);
  ctx->t_factorisation += now() - t1;
  ctx->factorisations += 1;
  return ok;
}

static double max_abs(const double *a, int count) {
  double out = 0.0;
  for (int i = 0; i < count; ++i) {
    double v = fabs(a[i]);
    if (isnan(v)) return v; /* as numpy's max: NaN propagates */
    if (v > out) out = v;
  }
  return out;
}

/* The predictor of step j: 2 q_j - q_{j-1} and the last multipliers (first step: q_0 + h v_0, 0). */
static void predict(fg_context *ctx, int j) {
  int n = ctx->n, N = ctx->N;
  double *x = ctx->x;
  if (j > 0) {
    const double *q_cur = ctx->q + (size_t)j * n, *q_prev = ctx->q + (size_t)(j - 1) * n;
    for (int i = 0; i < n; ++i) x[i] = 2.0 * q_cur[i] - q_prev[i];
    memcpy(x + n, ctx->lam + (size_t)(j - 1) * ctx->m, ctx->m * sizeof(double));
  } else {
    const double *q0 = ctx->q;
    for (int i = 0; i < n; ++i) x[i] = q0[i] + ctx->h * ctx->v0[i];
    for (int i = n; i < N; ++i) x[i] = 0.0;
  }
}

/* The Newton LU failed the pivot test at the current x: the caller computes a new order for
 * the Jacobian there (fg_jacobian evaluates at x) and the iteration resumes with that
 * factorisation, exactly where it stopped. */
static int newton_pivot(fg_context *ctx) {
  ctx->have_lu = 0;
  ctx->pivot_which = 0;
  ctx->newton_state.need_factor = 1;
  return FG_PIVOT;
}

static int sensitivity_step(fg_context *ctx);

/* One step; returns FG_OK, FG_NEWTON, FG_FOLD or FG_PIVOT (then call again to resume). */
static int take_step(fg_context *ctx) {
  int n = ctx->n, N = ctx->N, j = ctx->step, variant = variant_of(ctx, j);
  int first = j == 0;
  double *x = ctx->x;
  newton_state_t *st = &ctx->newton_state;
  if (!st->active) {
    predict(ctx, j);
    st->active = 1; st->k = 0; st->fresh_here = first; st->last_stale = 0; st->have_last = 0;
    st->previous = INFINITY;
    st->need_factor = !ctx->have_lu || first;
    for (int i = 0; i < N; ++i) ctx->residual[i] = NAN;
  }
  if (st->need_factor) {
    if (!factorise(ctx, &ctx->newton, j, x)) return newton_pivot(ctx);
    ctx->have_lu = 1;
    st->fresh_here = 1; st->have_last = 0; st->last_stale = 0; st->previous = INFINITY; /* factorised at x */
    st->need_factor = 0;
  }
  int converged = 0;
  double size = 0.0;
  while (st->k < ctx->max_iterations) {
    double t0 = now();
    evaluate(ctx, &ctx->res[variant], j, x, ctx->residual);
    double t1 = now();
    ctx->t_evaluation += t1 - t0;
    int finite = 1;
    for (int i = 0; i < N; ++i) if (!isfinite(ctx->residual[i])) { finite = 0; break; }
    if (finite) {
      memcpy(ctx->dx, ctx->residual, N * sizeof(double));
      lu_solve(&ctx->symbolic[0], &ctx->newton, ctx->dx, ctx->work);
      ctx->t_solve += now() - t1;
      size = max_abs(ctx->dx, n);
      finite = isfinite(size);
    }
    if (!finite || size > REFRESH_CONTRACTION * st->previous) {
      if (st->last_stale && st->have_last) {
        for (int i = 0; i < N; ++i) x[i] += ctx->last_dx[i]; /* undo the chord step that went astray */
      } else if (st->fresh_here || !finite) {
        break; /* a fresh Newton step diverged or left the domain */
      }
      if (!factorise(ctx, &ctx->newton, j, x)) return newton_pivot(ctx);
      st->fresh_here = 1; st->have_last = 0; st->last_stale = 0; st->previous = INFINITY;
      continue;
    }
    if (size > MAX_UPDATE) {
      double scale = MAX_UPDATE / size;
      for (int i = 0; i < N; ++i) ctx->dx[i] *= scale;
    }
    for (int i = 0; i < N; ++i) x[i] -= ctx->dx[i];
    st->k += 1;
    memcpy(ctx->last_dx, ctx->dx, N * sizeof(double));
    st->have_last = 1; st->last_stale = !st->fresh_here; st->fresh_here = 0;
    if (size <= ctx->tolerance * (1.0 + max_abs(x, n))
        && (max_abs(ctx->residual + n, ctx->m) <= ctx->constraint_tolerance || size == 0.0)) {
      converged = 1;
      break;
    }
    st->previous = size;
  }
  int k = st->k;
  st->active = 0;
  if (converged) {
    evaluate(ctx, &ctx->res[variant], j, x, ctx->work);
    double limit = ctx->constraint_tolerance > 1e3 * ctx->tolerance ? ctx->constraint_tolerance : 1e3 * ctx->tolerance;
    converged = max_abs(ctx->work + n, ctx->m) <= limit;
  }
  if (!converged) {
    double norm = 0.0;
    for (int i = 0; i < N; ++i) norm += ctx->residual[i] * ctx->residual[i];
    ctx->status_step = j; ctx->status_iterations = k; ctx->status_value = sqrt(norm);
    return FG_NEWTON;
  }
  double *q_next = ctx->q + (size_t)(j + 1) * n;
  memcpy(q_next, x, n * sizeof(double));
  memcpy(ctx->lam + (size_t)j * ctx->m, x + n, ctx->m * sizeof(double));
  ctx->iterations[j] = k;
  for (int g = 0; g < ctx->n_fold_groups; ++g) {
    int worst = -1;
    double worst_cosine = INFINITY;
    for (int e = ctx->group_start[g]; e < ctx->group_start[g + 1]; ++e) {
      const double *a = q_next + ctx->pair_a[e], *b = q_next + ctx->pair_b[e];
      double cosine = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
      if (cosine < worst_cosine) { worst_cosine = cosine; worst = e; }
    }
    if (worst >= 0 && worst_cosine < FOLD_COSINE) {
      ctx->status_step = j; ctx->status_index = worst; ctx->status_value = worst_cosine;
      ctx->step = j + 1; /* the step is stored: the caller reports it */
      return FG_FOLD;
    }
  }
  if (ctx->vel) {
    const double *q_cur = ctx->q + (size_t)j * n, *v_cur = ctx->vel + (size_t)j * n;
    double *v_next = ctx->vel + (size_t)(j + 1) * n;
    for (int i = 0; i < n; ++i) v_next[i] = 2.0 * (q_next[i] - q_cur[i]) / ctx->h - v_cur[i];
  }
  if (ctx->sensitivities) {
    ctx->sens_pending = 1;
    return sensitivity_step(ctx);
  }
  ctx->step = j + 1;
  return FG_OK;
}

/* Sensitivities of the converged step `step` (x holds it); then the step is done. */
static int sensitivity_step(fg_context *ctx) {
  int n = ctx->n, N = ctx->N, j = ctx->step, variant = variant_of(ctx, j), first = j == 0;
  const double *x = ctx->x;
  {
    double t0 = now();
    int n_p = ctx->n_p;
    if (!factorise(ctx, &ctx->exact, j, x)) { ctx->pivot_which = 1; return FG_PIVOT; } /* at the converged step */
    fn_t *fn = &ctx->sens_fn[variant];
    step_inputs(ctx, j, fn->arg, x);
    const double *s_cur = first ? ctx->s_zero : ctx->sens + (size_t)j * n * n_p;
    const double *s_prev = j > 1 ? ctx->sens + (size_t)(j - 1) * n * n_p : ctx->s_zero;
    fn->arg[8] = s_cur; fn->arg[9] = s_prev; fn->arg[10] = ctx->scheme == 1 ? ctx->sens_v : ctx->s_zero;
    fn->res[0] = ctx->rhs; /* (n_p, N) column-major = (N, n_p) row-major */
    fn->f(fn->arg, fn->res, fn->iw, fn->w, 0);
    double *s_next = ctx->sens + (size_t)(j + 1) * n * n_p;
    for (int a = 0; a < n_p; ++a) {
      for (int i = 0; i < N; ++i) ctx->column[i] = ctx->rhs[(size_t)i * n_p + a];
      lu_solve(&ctx->symbolic[1], &ctx->exact, ctx->column, ctx->work);
      for (int i = 0; i < n; ++i) s_next[(size_t)i * n_p + a] = -ctx->column[i];
    }
    if (ctx->scheme == 1) { /* dv_{j+1}/dp = 2 (S_{j+1} - S_j)/h - dv_j/dp */
      for (size_t i = 0; i < (size_t)n * n_p; ++i) ctx->sens_v[i] = 2.0 * (s_next[i] - s_cur[i]) / ctx->h - ctx->sens_v[i];
    }
    ctx->t_sensitivity += now() - t0;
  }
  ctx->sens_pending = 0;
  ctx->step = j + 1;
  return FG_OK;
}

/* Advance until step `until` (exclusive upper bound on steps taken) or a failure. */
int fg_run(fg_context *ctx, int until) {
  if (!ctx->symbolic[0].analysed || (ctx->sensitivities && !ctx->symbolic[1].analysed)) return FG_PIVOT;
  if (until > ctx->n_steps) until = ctx->n_steps;
  if (ctx->sens_pending) {
    int status = sensitivity_step(ctx);
    if (status != FG_OK) return status;
  }
  while (ctx->step < until) {
    int status = take_step(ctx);
    if (status != FG_OK) return status;
  }
  return FG_OK;
}

int fg_step(const fg_context *ctx) { return ctx->step; }

void fg_status(const fg_context *ctx, int *step, int *iterations, int *index, double *value) {
  *step = ctx->status_step; *iterations = ctx->status_iterations; *index = ctx->status_index;
  *value = ctx->status_value;
}

void fg_statistics(const fg_context *ctx, double *out) {
  out[0] = ctx->t_evaluation; out[1] = ctx->t_factorisation; out[2] = ctx->t_solve; out[3] = ctx->t_sensitivity;
  out[4] = (double)ctx->factorisations;
}
