/* Chord steps of Newton's method in compiled code (tca_casadi.solvers.native).
 *
 * Compiled together with CasADi's generated C code of the residual g(w, P) (its name given by
 * -DRESIDUAL=...). The Jacobian is factorised in Python (SuperLU: Pr A Pc = L U of A = J[:, order],
 * J's columns in the order `column`); here only its factors are used: each chord step solves
 * J step = g with two sparse triangular solves and evaluates the residual at w - step, as long as
 * the step cuts |g|_2 by the factor `contraction`. No Python runs between the steps.
 */
#include <math.h>
#include <string.h>

typedef long long casadi_int;
int RESIDUAL(const double** arg, double** res, casadi_int* iw, double* w, int mem);

#define MAX_ARGUMENTS 64

/* x with J x = b, from SuperLU's factors of A = J[:, order]: y = Pr b, L U z = y, x[column] = z */
static void factored_solve(int n, const int* Lp, const int* Li, const double* Lx,
                           const int* Up, const int* Ui, const double* Ux, const double* U_diagonal,
                           const int* perm_r, const int* column, const double* b, double* y, double* x) {
  int i, j, k;
  for (i = 0; i < n; i++) y[perm_r[i]] = b[i];
  for (j = 0; j < n; j++) {                         /* L: unit lower triangular, CSC */
    const double yj = y[j];
    if (yj == 0.0) continue;
    for (k = Lp[j]; k < Lp[j + 1]; k++) if (Li[k] > j) y[Li[k]] -= Lx[k] * yj;
  }
  for (j = n - 1; j >= 0; j--) {                    /* U: upper triangular, CSC */
    const double yj = (y[j] /= U_diagonal[j]);
    if (yj == 0.0) continue;
    for (k = Up[j]; k < Up[j + 1]; k++) if (Ui[k] < j) y[Ui[k]] -= Ux[k] * yj;
  }
  for (i = 0; i < n; i++) x[column[i]] = y[i];
}

static double largest(int n, const double* v) {   /* max |v|, NaN if any entry is NaN */
  double m = 0.0;
  int i;
  for (i = 0; i < n; i++) {
    const double a = fabs(v[i]);
    if (isnan(a)) return a;
    if (a > m) m = a;
  }
  return m;
}

static double squared(int n, const double* v) {
  double s = 0.0;
  int i;
  for (i = 0; i < n; i++) s += v[i] * v[i];
  return s;
}

/* Chord steps from w (g: the residual there) until max |g| <= tolerance.
 * Returns 0: converged; 1: a step did not contract |g|_2 by `contraction` or gave a residual that
 * is not finite (w and g stay at the last accepted point); 2: the residual at w is not finite; 3: `max_steps` steps taken.
 * `steps`: the steps accepted; `residual`: max |g| at the returned point. */
int chord_steps(int n, const double* P, double* w, double* g, double* work_n, double* iterate, double* trial_g,
                double* step, casadi_int* iw, double* work,
                const int* Lp, const int* Li, const double* Lx, const int* Up, const int* Ui, const double* Ux,
                const double* U_diagonal, const int* perm_r, const int* column,
                double tolerance, double contraction, int max_steps, int* steps, double* residual) {
  const double* arg[MAX_ARGUMENTS];
  double* res[MAX_ARGUMENTS];
  double norm = squared(n, g);
  double r = largest(n, g);
  int i;
  *steps = 0;
  for (;;) {
    *residual = r;
    if (!isfinite(r)) return 2;
    if (r <= tolerance) return 0;
    if (*steps >= max_steps) return 3;
    factored_solve(n, Lp, Li, Lx, Up, Ui, Ux, U_diagonal, perm_r, column, g, work_n, step);
    for (i = 0; i < n; i++) iterate[i] = w[i] - step[i];
    arg[0] = iterate;
    arg[1] = P;
    res[0] = trial_g;
    RESIDUAL(arg, res, iw, work, 0);
    const double trial_norm = squared(n, trial_g);
    if (!(trial_norm <= contraction * contraction * norm)) return 1;      /* also when not finite */
    memcpy(w, iterate, (size_t)n * sizeof(double));
    memcpy(g, trial_g, (size_t)n * sizeof(double));
    norm = trial_norm;
    r = largest(n, g);
    (*steps)++;
  }
}
