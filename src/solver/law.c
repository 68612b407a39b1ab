/* kergs law: the exact one-contact solve of the 2D Signorini-Coulomb law (docs/design.md: the per-step problem).
   v = Waa r + b. The solution is found by cases (open, stick, slip with v_t > 0, slip with v_t < 0):
   each case fixes which relations are equalities, which gives a closed-form candidate, accepted when
   it satisfies the remaining inequalities. No iteration, no PETSc calls: this runs in the sweep's
   inner loop. */
#include <kergs/law.h>

/* Relative threshold under which a determinant or a denominator is treated as zero. */
#define KERGS_LAW_SINGULAR (64 * PETSC_MACHINE_EPSILON)

/* Projection onto the Coulomb cone K = {|z_t| <= mu z_n} (2D), or onto {z_n >= 0} for ncomp == 1.
   K is spanned by the rays (1, +mu) and (1, -mu); its polar cone is {mu |z_t| <= -z_n}. Outside both,
   the projection lies on the boundary ray (1, mu sign(z_t)): p_n = (z_n + mu |z_t|) / (1 + mu^2). */
static inline void ProjectCoulombCone(PetscInt ncomp, const PetscReal z[], PetscReal mu, PetscReal p[])
{
  PetscReal at, pn;

  if (ncomp == 1) {
    p[0] = PetscMax(z[0], 0.0);
    return;
  }
  at = PetscAbsReal(z[1]);
  if (z[0] >= 0.0 && at <= mu * z[0]) { /* inside the cone (z_n >= 0 matters when mu = 0) */
    p[0] = z[0];
    p[1] = z[1];
  } else if (mu * at <= -z[0]) {
    p[0] = 0.0;
    p[1] = 0.0;
  } else {
    pn   = (z[0] + mu * at) / (1.0 + mu * mu);
    p[0] = pn;
    p[1] = z[1] >= 0 ? mu * pn : -mu * pn;
  }
}

void KergsLawNaturalMap(PetscInt ncomp, const PetscReal r[], const PetscReal v[], PetscReal mu, PetscReal rho, PetscBool active,
                        PetscReal e[])
{
  PetscReal z[KERGS_MAXCOMP] = {0.0}, p[KERGS_MAXCOMP];
  PetscInt  c;

  if (!active) {
    for (c = 0; c < ncomp; c++) e[c] = r[c];
    return;
  }
  /* De Saxce's modified velocity: v + mu |v_t| e_n makes the law a projection on the cone K. */
  z[0] = r[0] - rho * (v[0] + (ncomp > 1 ? mu * PetscAbsReal(v[1]) : 0.0));
  if (ncomp > 1) z[1] = r[1] - rho * v[1];
  ProjectCoulombCone(ncomp, z, mu, p);
  for (c = 0; c < ncomp; c++) e[c] = r[c] - p[c];
}

PetscReal KergsLawNaturalResidual2(PetscInt ncomp, const PetscReal r[], const PetscReal v[], PetscReal mu, PetscReal rho, PetscBool active)
{
  PetscReal e[KERGS_MAXCOMP], s = 0.0;

  KergsLawNaturalMap(ncomp, r, v, mu, rho, active, e);
  for (PetscInt c = 0; c < ncomp; c++) s += e[c] * e[c];
  return s;
}

/* Fallback when rounding rejects every case (the exact solution lies on a case boundary) or the block is
   degenerate: among the computed candidates, projected on the cone, keep the smallest natural residual.
   Any rho > 0 has the same zeros; 1 / max |W_ij| keeps rho v of the order of r even when W_nn is tiny. */
static KergsLawStatus SolveCoulomb2Fallback(const PetscReal W[], const PetscReal b[], PetscReal mu, PetscInt ncand,
                                            PetscReal cand[][KERGS_MAXCOMP], const KergsLawStatus status[], PetscReal r[])
{
  const PetscReal wmax = PetscMax(PetscMax(PetscAbsReal(W[0]), PetscAbsReal(W[1])), PetscMax(PetscAbsReal(W[2]), PetscAbsReal(W[3])));
  const PetscReal rho  = wmax > 0 ? 1.0 / wmax : 1.0;
  PetscReal       best = PETSC_MAX_REAL, p[KERGS_MAXCOMP], v[KERGS_MAXCOMP], res;
  KergsLawStatus  st   = KERGS_LAW_OPEN;
  PetscInt        k;

  r[0] = 0.0;
  r[1] = 0.0;
  for (k = 0; k < ncand; k++) {
    ProjectCoulombCone(2, cand[k], mu, p);
    v[0] = W[0] * p[0] + W[1] * p[1] + b[0];
    v[1] = W[2] * p[0] + W[3] * p[1] + b[1];
    res  = KergsLawNaturalResidual2(2, p, v, mu, rho, PETSC_TRUE);
    if (res < best) {
      best = res;
      r[0] = p[0];
      r[1] = p[1];
      st   = status[k];
    }
  }
  return st;
}

/* The active, closing 2D case (b_n < 0): r_n > 0 at the solution, so v_n = 0 and one of stick, slip+,
   slip- holds. Waa = [Wnn Wnt; Wtn Wtt] row-major. */
static inline KergsLawStatus SolveCoulomb2(const PetscReal W[], const PetscReal b[], PetscReal mu, PetscReal r[])
{
  const PetscReal Wnn = W[0], Wnt = W[1], Wtn = W[2], Wtt = W[3], bn = b[0], bt = b[1];
  const PetscReal det = Wnn * Wtt - Wnt * Wtn;
  PetscReal       cand[4][KERGS_MAXCOMP], den, rn, rt, vt;
  KergsLawStatus  status[4];
  PetscInt        ncand = 0;

  /* Stick: v = 0, r = -Waa^{-1} b (Cramer). Divisions only by denominators known to be nonzero (so that
     -fp_trap never fires); a case with a singular denominator gives no candidate. */
  if (det > KERGS_LAW_SINGULAR * PetscAbsReal(Wnn * Wtt)) {
    rn = (Wnt * bt - Wtt * bn) / det;
    rt = (Wtn * bn - Wnn * bt) / det;
    if (rn >= 0 && PetscAbsReal(rt) <= mu * rn) {
      r[0] = rn;
      r[1] = rt;
      return KERGS_LAW_STICK;
    }
    cand[ncand][0]  = rn;
    cand[ncand][1]  = rt;
    status[ncand++] = KERGS_LAW_STICK;
  }
  /* Slip with v_t > 0: r_t = -mu r_n, v_n = (Wnn - mu Wnt) r_n + b_n = 0 (r_n > 0 needs den > 0). */
  den = Wnn - mu * Wnt;
  if (den > KERGS_LAW_SINGULAR * (Wnn + mu * PetscAbsReal(Wnt))) {
    rn = -bn / den;
    vt = (Wtn - mu * Wtt) * rn + bt;
    if (vt >= 0) {
      r[0] = rn;
      r[1] = -mu * rn;
      return KERGS_LAW_SLIP_POS;
    }
    cand[ncand][0]  = rn;
    cand[ncand][1]  = -mu * rn;
    status[ncand++] = KERGS_LAW_SLIP_POS;
  }
  /* Slip with v_t < 0: r_t = +mu r_n, v_n = (Wnn + mu Wnt) r_n + b_n = 0. */
  den = Wnn + mu * Wnt;
  if (den > KERGS_LAW_SINGULAR * (Wnn + mu * PetscAbsReal(Wnt))) {
    rn = -bn / den;
    vt = (Wtn + mu * Wtt) * rn + bt;
    if (vt <= 0) {
      r[0] = rn;
      r[1] = mu * rn;
      return KERGS_LAW_SLIP_NEG;
    }
    cand[ncand][0]  = rn;
    cand[ncand][1]  = mu * rn;
    status[ncand++] = KERGS_LAW_SLIP_NEG;
  }
  cand[ncand][0]  = 0.0;
  cand[ncand][1]  = 0.0;
  status[ncand++] = KERGS_LAW_OPEN;
  return SolveCoulomb2Fallback(W, b, mu, ncand, cand, status, r);
}

KergsLawStatus KergsLawSolve(PetscInt ncomp, const PetscReal Waa[], const PetscReal b[], PetscReal mu, PetscBool active, PetscReal r[])
{
  if (!active || !(b[0] < 0)) {
    /* Inactive, or separating: r = 0 gives v = b with v_n >= 0 (a solution of the law). */
    r[0] = 0.0;
    if (ncomp > 1) r[1] = 0.0;
    return active ? KERGS_LAW_OPEN : KERGS_LAW_INACTIVE;
  }
  if (ncomp == 1) {
    /* Signorini alone: v_n = Wnn r_n + b_n = 0 with b_n < 0. A degenerate block (Wnn <= 0) gets r = 0. */
    if (!(Waa[0] > 0)) {
      r[0] = 0.0;
      return KERGS_LAW_OPEN;
    }
    r[0] = -b[0] / Waa[0];
    return KERGS_LAW_STICK;
  }
  return SolveCoulomb2(Waa, b, mu, r);
}

/* Shared by the Alart-Curnier functions: A and B zeroed when wanted; for an inactive contact (r = 0) F = r, J = I, and
   true is returned (nothing more to compute). */
static inline PetscBool StartJacobian(PetscInt nc, const PetscScalar r[], PetscBool active, PetscReal F[], PetscReal A[], PetscReal B[])
{
  if (A)
    for (PetscInt i = 0; i < nc * nc; i++) A[i] = B[i] = 0.0;
  if (active) return PETSC_FALSE;
  for (PetscInt c = 0; c < nc; c++) {
    F[c] = PetscRealPart(r[c]);
    if (A) A[c * nc + c] = 1.0;
  }
  return PETSC_TRUE;
}

/* Alart-Curnier function of one contact and an element of its generalized Jacobian (law.h). Each branch is a piece
   where F is linear in (r, u): open (F = r_n), closed (F_n = rho u_n), stick (F_t = rho u_t), slip (F_t = r_t - sign(z)
   mu (r_n - rho u_n)). On a boundary between pieces (xi = 0: open; |z| = tau: slip) the row chosen stays
   nonsingular. */
void KergsLawAlartCurnier(PetscInt nc, const PetscScalar r[], const PetscScalar u[], PetscReal mu, PetscReal rho, PetscBool active,
                          PetscReal F[], PetscReal A[], PetscReal B[])
{
  PetscReal xi, tau, z;

  if (StartJacobian(nc, r, active, F, A, B)) return;
  xi = PetscRealPart(r[0]) - rho * PetscRealPart(u[0]);
  if (xi > 0) { /* closed: F_n = rho u_n */
    F[0] = rho * PetscRealPart(u[0]);
    if (A) B[0] = rho;
  } else { /* open: F_n = r_n */
    F[0] = PetscRealPart(r[0]);
    if (A) A[0] = 1.0;
  }
  if (nc == 1) return;
  tau = mu * PetscMax(xi, 0.0);
  z   = PetscRealPart(r[1]) - rho * PetscRealPart(u[1]);
  if (PetscAbsReal(z) < tau) { /* stick: F_t = rho u_t (ties go to slip, whose row stays nonsingular) */
    F[1] = rho * PetscRealPart(u[1]);
    if (A) B[3] = rho;
  } else { /* slip, or open: F_t = r_t - sign(z) tau, tau depending on r_n - rho u_n while closed */
    const PetscReal s = z >= 0 ? 1.0 : -1.0;
    F[1]              = PetscRealPart(r[1]) - s * tau;
    if (A) {
      A[3] = 1.0;
      if (xi > 0) {
        A[2] = -s * mu;
        B[2] = s * mu * rho;
      }
    }
  }
}

/* phi_eps(x) = (x + sqrt(x^2 + 4 eps^2)) / 2 and its derivative (1 + x / sqrt(x^2 + 4 eps^2)) / 2 = phi / sqrt(...) */
static inline PetscReal SmoothPlus(PetscReal x, PetscReal eps, PetscReal *dphi)
{
  const PetscReal big = PetscMax(PetscAbsReal(x), 2.0 * eps), safe = 0.25 * PetscSqrtReal(PETSC_MAX_REAL);
  /* sqrt(x^2 + 4 eps^2); hypot, which avoids overflow and underflow of the squares, only where they could happen
     (sqrt(DBL_MIN) < 1 / safe): it costs several times as much, and this runs for every contact at every trial point of
     every line search */
  const PetscReal root = big > 1.0 / safe && big < safe ? PetscSqrtReal(x * x + 4.0 * eps * eps) : PetscHypotReal(x, 2.0 * eps);
  PetscReal       phi;

  if (!(root > 0)) { /* x = eps = 0 */
    *dphi = 0.5;
    return 0.0;
  }
  phi   = x >= 0 ? 0.5 * (x + root) : 2.0 * eps * eps / (root - x); /* no cancellation for x << 0 */
  *dphi = phi / root;                                               /* = (1 + x / root) / 2 */
  return phi;
}

void KergsLawAlartCurnierSmoothed(PetscInt nc, const PetscScalar r[], const PetscScalar u[], PetscReal mu, PetscReal rho, PetscBool active,
                                  PetscReal eps, PetscReal F[], PetscReal A[], PetscReal B[])
{
  PetscReal xi, dxi, tau, z, a, b;

  if (StartJacobian(nc, r, active, F, A, B)) return;
  xi   = PetscRealPart(r[0]) - rho * PetscRealPart(u[0]);
  tau  = SmoothPlus(xi, eps, &dxi); /* max(0, xi), smoothed */
  F[0] = PetscRealPart(r[0]) - tau;
  if (A) {
    A[0] = 1.0 - dxi;
    B[0] = dxi * rho;
  }
  if (nc == 1) return;
  tau *= mu;
  z    = PetscRealPart(r[1]) - rho * PetscRealPart(u[1]);
  F[1] = rho * PetscRealPart(u[1]) + SmoothPlus(z - tau, eps, &a) - SmoothPlus(-z - tau, eps, &b);
  if (A) { /* dz = dr_t - rho du_t, dtau = mu dxi (dr_n - rho du_n) */
    A[3] = a + b;
    A[2] = mu * dxi * (b - a);
    B[3] = rho * (1.0 - a - b);
    B[2] = -rho * mu * dxi * (b - a);
  }
}
