/* fcomp's stepping loop (fcomp/compiled.py, stepping_loop): a CasADi step function
   STEP(x, u, dt, p) -> x_next applied sample by sample,

     X[0] = x0,   X[k + 1] = STEP(X[k], u[k], dt[k], p),   k = 0 .. n - 1.

   A template: fcomp.compiled.c_source fills its placeholders (a NAME between two at signs:
   the step function's name, the numbers of states NX and inputs NU). The step function is
   CasADi's generated C, placed before this file. Returns 0, or k + 1 when the step failed
   at sample k. */
#include <string.h>
int fcomp_loop(int n, const double* x0, const double* u, const double* dt,
               const double* p, double* X) {
  casadi_int sz_arg, sz_res, sz_iw, sz_w;
  @STEP@_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
  const casadi_real* arg[sz_arg > 4 ? sz_arg : 4];
  casadi_real* res[sz_res > 1 ? sz_res : 1];
  casadi_int iw[sz_iw + 1];
  casadi_real w[sz_w + 1];
  memcpy(X, x0, @NX@ * sizeof(double));
  for (int k = 0; k < n; ++k) {
    arg[0] = X + k * @NX@; arg[1] = u + k * @NU@; arg[2] = dt + k; arg[3] = p;
    res[0] = X + (k + 1) * @NX@;
    if (@STEP@(arg, res, iw, w, 0)) return k + 1;
  }
  return 0;
}
