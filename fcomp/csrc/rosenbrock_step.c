#include <math.h>
#include <string.h>
/* fcomp's adaptive Rosenbrock method over sample intervals: the compiled loop of the
   simulation engine (fcomp/simulation.py, class Rodas4).

   A template: fcomp.compiled.c_source fills its placeholders (a NAME between two at
   signs) before compiling. The method's coefficients (NS, GAMMA, RA, RC, RM, RE, ALPHA,
   GAMS, ORDER) and the step-size control (SAFETY, FACMIN, FACMAX) come from the one
   definition of the tableau, fcomp/rosenbrock.py (RODAS4 and STEP_CONTROL, as C literals by
   fcomp.rosenbrock.c_coefficients); the stage loop is that of
   fcomp.rosenbrock.rosenbrock_stages (Hairer & Wanner, Solving ODEs II, 2nd ed., Springer
   1996, Sec. IV.7, rodas.f):

     (I/(h*gamma) - J) K_i = f(t + alpha_i*h, x + sum_j a_ij K_j) + h*gamma_i*f_t
                             + sum_j c_ij/h K_j,
     x_new = x + sum_i m_i K_i,   err = sum_i e_i K_i,

   solved in the scaled states x/sc (D = diag(sc)). The model (F, J, NX states, NU inputs)
   is CasADi's generated C, placed before this file: F(x, u, p) -> dx/dt and
   J(x, u, p) -> (df/dx, df/du), dense, column-major.
   opts = {rtol, atol, h_min, max_steps}; info = {status, interval, t, h, accepted, rejected}
   status: 0 ok, 1 step size below h_min, 2 too many steps, 3 non-finite model output. */
#define NX @NX@
#define NU @NU@
#define NUB (NU > 0 ? NU : 1)
#define NS @NS@
#define NS1 (NS > 1 ? NS - 1 : 1)
static const double GAM = @GAMMA@;
static const double RA[NS][NS1] = @RA@;
static const double RC[NS][NS1] = @RC@;
static const double RM[NS] = @RM@;
static const double RE[NS] = @RE@;
static const double ALPHA[NS] = @ALPHA@;
static const double GAMS[NS] = @GAMS@;

static int lu_factor(double* A, int* piv) {
  for (int k = 0; k < NX; ++k) {
    int p = k;
    double amax = fabs(A[k * NX + k]);
    for (int i = k + 1; i < NX; ++i)
      if (fabs(A[i * NX + k]) > amax) { amax = fabs(A[i * NX + k]); p = i; }
    piv[k] = p;
    if (!(amax > 0.0) || !isfinite(amax)) return 1;
    if (p != k)
      for (int j = 0; j < NX; ++j) { double t = A[k * NX + j]; A[k * NX + j] = A[p * NX + j]; A[p * NX + j] = t; }
    const double inv = 1.0 / A[k * NX + k];
    for (int i = k + 1; i < NX; ++i) {
      const double l = (A[i * NX + k] *= inv);
      if (l != 0.0)
        for (int j = k + 1; j < NX; ++j) A[i * NX + j] -= l * A[k * NX + j];
    }
  }
  return 0;
}

static void lu_solve(const double* A, const int* piv, double* b) {
  for (int k = 0; k < NX; ++k)
    if (piv[k] != k) { double t = b[k]; b[k] = b[piv[k]]; b[piv[k]] = t; }
  for (int i = 1; i < NX; ++i) {
    double s = b[i];
    for (int j = 0; j < i; ++j) s -= A[i * NX + j] * b[j];
    b[i] = s;
  }
  for (int i = NX - 1; i >= 0; --i) {
    double s = b[i];
    for (int j = i + 1; j < NX; ++j) s -= A[i * NX + j] * b[j];
    b[i] = s / A[i * NX + i];
  }
}

int fcomp_ode(int n, const double* x0, const double* U, const double* dU, const double* dt,
              const double* p, const double* sc, const double* opts, double* h_io,
              double* X, double* info) {
  casadi_int a1, r1, i1, w1, a2, r2, i2, w2;
  @F@_work(&a1, &r1, &i1, &w1);
  @J@_work(&a2, &r2, &i2, &w2);
  casadi_int sz_arg = a1 > a2 ? a1 : a2, sz_res = r1 > r2 ? r1 : r2;
  casadi_int sz_iw = i1 > i2 ? i1 : i2, sz_w = w1 > w2 ? w1 : w2;
  const casadi_real* arg[sz_arg > 3 ? sz_arg : 3];
  casadi_real* res[sz_res > 2 ? sz_res : 2];
  casadi_int iw[sz_iw + 1];
  casadi_real w[sz_w + 1];
  double x[NX], xn[NX], f0[NX], J[NX * NX], Ju[NX * NUB], ft[NX], M[NX * NX];
  double K[NS][NX], Y[NX], fy[NX], uu[NUB];
  int piv[NX];
  const double rtol = opts[0], atol = opts[1], hmin = opts[2], max_steps = opts[3];
  double h = *h_io, nacc = info[4], nrej = info[5], t = 0.0;
  int status = 0, k = 0;
  memcpy(x, x0, NX * sizeof(double));
  memcpy(X, x0, NX * sizeof(double));
  for (k = 0; k < n && status == 0; ++k) {
    const double T = dt[k];
    const double* u0 = U + k * NU;
    const double* du = dU + k * NU;
    int rejected = 0, fresh = 0;
    t = 0.0;
    while (T - t > 1e-12 * T) {
      double hs = h;
      int clipped = 0, bad = 0;
      if (hs >= T - t || (T - t) - hs < 0.01 * hs) { hs = T - t; clipped = 1; }
      if (!fresh) {  /* f and Jacobians at (t, x): once per accepted state */
        for (int i = 0; i < NU; ++i) uu[i] = u0[i] + du[i] * t;
        arg[0] = x; arg[1] = uu; arg[2] = p; res[0] = f0;
        if (@F@(arg, res, iw, w, 0)) { status = 3; break; }
        res[0] = J; res[1] = Ju;
        if (@J@(arg, res, iw, w, 0)) { status = 3; break; }
        for (int i = 0; i < NX; ++i) {
          double s = 0.0;
          for (int j = 0; j < NU; ++j) s += Ju[i + j * NX] * du[j];
          ft[i] = s;
          if (!isfinite(f0[i]) || !isfinite(s)) status = 3;
          for (int j = 0; j < NX; ++j) if (!isfinite(J[i + j * NX])) status = 3;
        }
        if (status) break;
        fresh = 1;
      }
      /* scaled iteration matrix  I/(h*gamma) - D^-1 J D,  D = diag(sc) */
      for (int i = 0; i < NX; ++i)
        for (int j = 0; j < NX; ++j)
          M[i * NX + j] = (i == j ? 1.0 / (hs * GAM) : 0.0) - J[i + j * NX] * sc[j] / sc[i];
      if (lu_factor(M, piv)) bad = 1;
      for (int st = 0; st < NS && !bad; ++st) {
        if (st == 0) {
          memcpy(fy, f0, NX * sizeof(double));
        } else {
          for (int i = 0; i < NX; ++i) {
            double y = x[i];
            for (int j = 0; j < st; ++j) y += RA[st][j] * K[j][i];
            Y[i] = y;
          }
          for (int i = 0; i < NU; ++i) uu[i] = u0[i] + du[i] * (t + ALPHA[st] * hs);
          arg[0] = Y; arg[1] = uu; arg[2] = p; res[0] = fy;
          if (@F@(arg, res, iw, w, 0)) { bad = 1; break; }
        }
        for (int i = 0; i < NX; ++i) {
          double r = fy[i] + hs * GAMS[st] * ft[i];
          for (int j = 0; j < st; ++j) r += RC[st][j] / hs * K[j][i];
          K[st][i] = r / sc[i];
        }
        lu_solve(M, piv, K[st]);
        for (int i = 0; i < NX; ++i) K[st][i] *= sc[i];
      }
      double en = 1e10;
      if (!bad) {
        double s = 0.0;
        for (int i = 0; i < NX; ++i) {
          double v = x[i], ek = 0.0;
          for (int j = 0; j < NS; ++j) { v += RM[j] * K[j][i]; ek += RE[j] * K[j][i]; }
          xn[i] = v;
          const double e = ek / (atol * sc[i] + rtol * fmax(fabs(x[i]), fabs(v)));
          s += e * e;
          if (!isfinite(v)) bad = 1;
        }
        en = sqrt(s / NX);
        if (bad || !isfinite(en)) en = 1e10;
      }
      double fac = @SAFETY@ * pow(en, -1.0 / @ORDER@);
      if (!(fac <= @FACMAX@)) fac = @FACMAX@;
      if (fac < @FACMIN@) fac = @FACMIN@;
      if (en <= 1.0) {
        memcpy(x, xn, NX * sizeof(double));
        t += hs;
        nacc += 1.0;
        fresh = 0;
        if (rejected) fac = fmin(fac, 1.0);
        rejected = 0;
        const double hn = hs * fac;
        h = (clipped && fac >= 1.0) ? fmax(h, hn) : hn;
      } else {
        nrej += 1.0;
        rejected = 1;
        h = hs * fac;
        if (h < hmin) { status = 1; break; }
      }
      if (nacc + nrej >= max_steps) { status = 2; break; }
    }
    if (status == 0) memcpy(X + (k + 1) * NX, x, NX * sizeof(double));
  }
  *h_io = h;
  info[0] = status; info[1] = status ? k - 1 : n; info[2] = t; info[3] = h;
  info[4] = nacc; info[5] = nrej;
  return status;
}
