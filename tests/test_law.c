/* Tests of the exact one-contact law (src/solver/law.c): for thousands of random SPD 2x2 blocks and right-hand
   sides, the returned r satisfies the Signorini-Coulomb law to rounding, the natural-map residual vanishes
   there and not at a perturbed r; plus hand-made cases, ncomp = 1, inactive contacts and degenerate blocks. */
#include "testing.h"

static const char help[] = "Tests of the one-contact Signorini-Coulomb law.\n";

/* splitmix64: a small reproducible generator, independent of the platform's rand(). */
static PetscReal Uniform(unsigned long long *state, PetscReal lo, PetscReal hi)
{
  unsigned long long z = (*state += 0x9E3779B97F4A7C15ULL);

  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z = z ^ (z >> 31);
  return lo + (hi - lo) * ((PetscReal)(z >> 11) / 9007199254740992.0);
}

static void Velocity(PetscInt nc, const PetscReal W[], const PetscReal r[], const PetscReal b[], PetscReal v[])
{
  PetscInt i, j;

  for (i = 0; i < nc; i++) {
    v[i] = b[i];
    for (j = 0; j < nc; j++) v[i] += W[i * nc + j] * r[j];
  }
}

/* Worst violation of the law by (r, v = W r + b), relative to the scales of the problem: impulses are
   measured against rs = |r| + |b| / Wnn, velocities against vs = |b| + |W| |r|. Returns 0 for an exact law. */
static PetscReal LawViolation(PetscInt nc, const PetscReal W[], const PetscReal b[], PetscReal mu, KergsLawStatus st, const PetscReal r[])
{
  PetscReal v[2], rs, vs, viol = 0.0, rt = nc > 1 ? r[1] : 0.0, vt;

  Velocity(nc, W, r, b, v);
  vt = nc > 1 ? v[1] : 0.0;
  rs = PetscAbsReal(r[0]) + PetscAbsReal(rt) + (PetscAbsReal(b[0]) + (nc > 1 ? PetscAbsReal(b[1]) : 0.0)) / W[0];
  vs = PetscAbsReal(b[0]) + (nc > 1 ? PetscAbsReal(b[1]) : 0.0) + W[0] * rs +
       (nc > 1 ? (PetscAbsReal(W[1]) + PetscAbsReal(W[3])) * rs : 0.0);
  viol = PetscMax(viol, -r[0] / rs);                            /* r_n >= 0 */
  viol = PetscMax(viol, (PetscAbsReal(rt) - mu * r[0]) / rs);   /* |r_t| <= mu r_n */
  viol = PetscMax(viol, -v[0] / vs);                            /* v_n >= 0 */
  viol = PetscMax(viol, PetscAbsReal(v[0] * r[0]) / (vs * rs)); /* v_n r_n = 0 */
  switch (st) {
  case KERGS_LAW_OPEN:
    viol = PetscMax(viol, (PetscAbsReal(r[0]) + PetscAbsReal(rt)) / rs);
    if (b[0] < 0) viol = PetscMax(viol, 1.0); /* a closing contact cannot stay open */
    break;
  case KERGS_LAW_STICK:
    viol = PetscMax(viol, (PetscAbsReal(v[0]) + PetscAbsReal(vt)) / vs);
    break;
  case KERGS_LAW_SLIP_POS:
    viol = PetscMax(viol, -vt / vs);
    viol = PetscMax(viol, PetscAbsReal(rt + mu * r[0]) / rs);
    break;
  case KERGS_LAW_SLIP_NEG:
    viol = PetscMax(viol, vt / vs);
    viol = PetscMax(viol, PetscAbsReal(rt - mu * r[0]) / rs);
    break;
  default:
    viol = PetscMax(viol, 1.0); /* active contacts are never reported inactive */
  }
  /* Coulomb in every status: sliding (|v_t| > 0) needs r_t = -mu r_n sign(v_t) */
  if (PetscAbsReal(vt) > 1e-10 * vs) viol = PetscMax(viol, PetscAbsReal(rt + (vt > 0 ? mu : -mu) * r[0]) / rs);
  return viol;
}

static PetscErrorCode TestRandom2D(void)
{
  const PetscReal    mus[4] = {0.0, 0.3, 1.0, 5.0};
  const PetscInt     ncase  = 40000;
  unsigned long long seed   = 12345;
  PetscReal          worst = 0.0, worst_res = 0.0, min_ratio = PETSC_MAX_REAL;
  PetscInt           k, count[5] = {0, 0, 0, 0, 0}, nonfinite = 0, nviol = 0, nres = 0;

  PetscFunctionBeginUser;
  for (k = 0; k < ncase; k++) {
    PetscReal      W[4], b[2], r[2], rp[2], v[2], vp[2], d[2], mu = mus[k % 4], a, dd, rho, res, resp, scale, viol;
    KergsLawStatus st;

    a    = PetscPowReal(10.0, Uniform(&seed, -2, 2));
    dd   = PetscPowReal(10.0, Uniform(&seed, -2, 2));
    W[0] = a;
    W[3] = dd;
    W[1] = W[2] = Uniform(&seed, -0.98, 0.98) * PetscSqrtReal(a * dd);
    scale       = PetscPowReal(10.0, Uniform(&seed, -3, 3));
    b[0]        = scale * Uniform(&seed, -1, 1);
    b[1]        = scale * Uniform(&seed, -1, 1);
    st          = KergsLawSolve(2, W, b, mu, PETSC_TRUE, r);
    if (PetscIsInfOrNanReal(r[0]) || PetscIsInfOrNanReal(r[1])) {
      nonfinite++;
      continue;
    }
    viol = LawViolation(2, W, b, mu, st, r);
    if (!(viol <= 1e-12)) nviol++;
    worst = PetscMax(worst, viol);
    count[st]++;

    /* natural-map residual: ~0 at r, clearly positive at r + d */
    rho = 1.0 / W[0];
    Velocity(2, W, r, b, v);
    scale = PetscAbsReal(r[0]) + PetscAbsReal(r[1]) + rho * (PetscAbsReal(b[0]) + PetscAbsReal(b[1]));
    res   = PetscSqrtReal(KergsLawNaturalResidual2(2, r, v, mu, rho, PETSC_TRUE)) / scale;
    if (!(res <= 1e-12)) nres++;
    worst_res = PetscMax(worst_res, res);
    d[0]      = 1e-3 * scale * Uniform(&seed, -1, 1);
    d[1]      = 1e-3 * scale * Uniform(&seed, -1, 1);
    rp[0]     = r[0] + d[0];
    rp[1]     = r[1] + d[1];
    Velocity(2, W, rp, b, vp);
    resp      = PetscSqrtReal(KergsLawNaturalResidual2(2, rp, vp, mu, rho, PETSC_TRUE));
    min_ratio = PetscMin(min_ratio, resp / PetscSqrtReal(d[0] * d[0] + d[1] * d[1]));
  }
  PetscCall(PetscPrintf(PETSC_COMM_SELF,
                        "random 2D: %" PetscInt_FMT " cases (open %" PetscInt_FMT ", stick %" PetscInt_FMT ", slip+ %" PetscInt_FMT
                        ", slip- %" PetscInt_FMT ")\n",
                        ncase, count[KERGS_LAW_OPEN], count[KERGS_LAW_STICK], count[KERGS_LAW_SLIP_POS], count[KERGS_LAW_SLIP_NEG]));
  PetscCall(Check((PetscBool)(nonfinite == 0), "random 2D: cases with a non-finite r", nonfinite, 0));
  PetscCall(Check((PetscBool)(nviol == 0), "random 2D: law satisfied to 1e-12 (worst relative violation)", worst, 1e-12));
  PetscCall(Check((PetscBool)(nres == 0), "random 2D: natural residual at r <= 1e-12 (worst, relative)", worst_res, 1e-12));
  PetscCall(Check(
      (PetscBool)(count[KERGS_LAW_OPEN] && count[KERGS_LAW_STICK] && count[KERGS_LAW_SLIP_POS] && count[KERGS_LAW_SLIP_NEG]),
      "random 2D: every status reached (open, stick, slip+, slip-: the rarest)",
      PetscMin(PetscMin(count[KERGS_LAW_OPEN], count[KERGS_LAW_STICK]), PetscMin(count[KERGS_LAW_SLIP_POS], count[KERGS_LAW_SLIP_NEG])),
      1));
  PetscCall(Check((PetscBool)(min_ratio > 1e-3), "random 2D: natural residual at r + d >= 1e-3 |d| (smallest ratio)", min_ratio, 1e-3));
  PetscFunctionReturn(0);
}

/* Cases with a solution known by hand. */
static PetscErrorCode TestHandCases(void)
{
  const PetscReal Id[4] = {1, 0, 0, 1}, W[4] = {2, 1, 1, 2};
  PetscReal       r[2], res;
  KergsLawStatus  st;

  PetscFunctionBeginUser;
  /* W = I, b = (-1, 0.1), mu = 0.3: stick with r = -b */
  st = KergsLawSolve(2, Id, (PetscReal[]){-1, 0.1}, 0.3, PETSC_TRUE, r);
  PetscCall(Checkf((PetscBool)(st == KERGS_LAW_STICK && r[0] == 1 && r[1] == -0.1), r[1], -0.1,
                   "stick case: status stick, r = (1, -0.1) (status %d, r_n %g)", (int)st, (double)r[0]));
  /* W = I, b = (-1, 1), mu = 0.3: slip with v_t = 0.7 > 0, r = (1, -0.3) */
  st = KergsLawSolve(2, Id, (PetscReal[]){-1, 1}, 0.3, PETSC_TRUE, r);
  PetscCall(Checkf((PetscBool)(st == KERGS_LAW_SLIP_POS && r[0] == 1 && PetscAbsReal(r[1] + 0.3) < 1e-15), r[1], -0.3,
                   "slip+ case: status slip+, r = (1, -0.3) (status %d, r_n %g)", (int)st, (double)r[0]));
  /* W = I, b = (-2, -1), mu = 0.25: slip with v_t < 0, r = (2, 0.5) */
  st = KergsLawSolve(2, Id, (PetscReal[]){-2, -1}, 0.25, PETSC_TRUE, r);
  PetscCall(Checkf((PetscBool)(st == KERGS_LAW_SLIP_NEG && r[0] == 2 && r[1] == 0.5), r[1], 0.5,
                   "slip- case: status slip-, r = (2, 0.5) (status %d, r_n %g)", (int)st, (double)r[0]));
  /* mu = 0 with coupling: r_t = 0, r_n = -b_n / Wnn = 0.5 */
  st = KergsLawSolve(2, W, (PetscReal[]){-1, 0.3}, 0.0, PETSC_TRUE, r);
  PetscCall(Checkf((PetscBool)((st == KERGS_LAW_SLIP_POS || st == KERGS_LAW_SLIP_NEG) && r[0] == 0.5 && r[1] == 0), r[0], 0.5,
                   "frictionless case: sliding, r = (0.5, 0) (status %d, r_t %g)", (int)st, (double)r[1]));
  /* separating: r = 0 */
  r[0] = r[1] = 7;
  st          = KergsLawSolve(2, W, (PetscReal[]){0.5, -3}, 1.0, PETSC_TRUE, r);
  PetscCall(Checkf((PetscBool)(st == KERGS_LAW_OPEN && r[0] == 0 && r[1] == 0), PetscAbsReal(r[0]) + PetscAbsReal(r[1]), 0,
                   "open case: status open, r = 0 (status %d)", (int)st));
  /* inactive: r = 0 whatever b, and the natural residual is |r|^2 */
  r[0] = r[1] = 7;
  st          = KergsLawSolve(2, W, (PetscReal[]){-5, 1}, 1.0, PETSC_FALSE, r);
  PetscCall(Checkf((PetscBool)(st == KERGS_LAW_INACTIVE && r[0] == 0 && r[1] == 0), PetscAbsReal(r[0]) + PetscAbsReal(r[1]), 0,
                   "inactive case: status inactive, r = 0 (status %d)", (int)st));
  res = KergsLawNaturalResidual2(2, (PetscReal[]){1, 2}, (PetscReal[]){-3, 0}, 0.5, 1.0, PETSC_FALSE);
  PetscCall(Check((PetscBool)(res == 5.0), "inactive residual is |r|^2", res, 5.0));
  /* the De Saxce residual of a sliding solution is exactly zero: r = (1, -0.3), v = (0, 0.7) */
  res = KergsLawNaturalResidual2(2, (PetscReal[]){1, -0.3}, (PetscReal[]){0, 0.7}, 0.3, 1.0, PETSC_TRUE);
  PetscCall(Check((PetscBool)(res < 1e-30), "sliding solution: natural residual zero", res, 0));
  /* ... and not for the same r with v_t of the wrong sign */
  res = KergsLawNaturalResidual2(2, (PetscReal[]){1, -0.3}, (PetscReal[]){0, -0.7}, 0.3, 1.0, PETSC_TRUE);
  PetscCall(Check((PetscBool)(res > 0.1), "sliding the wrong way: natural residual > 0.1", res, 0.1));
  PetscFunctionReturn(0);
}

/* Solutions on the stick/slip boundary (|r_t| = mu r_n with v = 0), where rounding can reject every case
   and the fallback must still return a point that satisfies the law. */
static PetscErrorCode TestBoundary2D(void)
{
  const PetscReal    mus[3] = {0.3, 1.0, 5.0};
  unsigned long long seed   = 4242;
  PetscReal          worst = 0.0, worst_dr = 0.0;
  PetscInt           k, nunique = 0, nviol = 0;

  PetscFunctionBeginUser;
  for (k = 0; k < 30000; k++) {
    PetscReal      W[4], b[2], r[2], rs[2], mu = mus[k % 3], a, dd, viol;
    KergsLawStatus st;

    a    = PetscPowReal(10.0, Uniform(&seed, -2, 2));
    dd   = PetscPowReal(10.0, Uniform(&seed, -2, 2));
    W[0] = a;
    W[3] = dd;
    W[1] = W[2] = Uniform(&seed, -0.9, 0.9) * PetscSqrtReal(a * dd);
    rs[0]       = Uniform(&seed, 0.1, 1.0);
    rs[1]       = (k % 2 ? mu : -mu) * rs[0];
    b[0]        = -(W[0] * rs[0] + W[1] * rs[1]);
    b[1]        = -(W[2] * rs[0] + W[3] * rs[1]);
    st          = KergsLawSolve(2, W, b, mu, PETSC_TRUE, r);
    viol        = LawViolation(2, W, b, mu, st, r);
    if (!(viol <= 1e-12)) nviol++;
    worst = PetscMax(worst, viol);
    /* With v_n = 0, r_n = (-b_n - Wnt r_t) / Wnn and v_t = S r_t + c (S = Wtt - Wtn Wnt / Wnn > 0); when
       mu |Wnt| < Wnn the cone becomes a bounded interval of r_t and the law a strictly monotone variational
       inequality on it: the solution is unique, hence the constructed one. */
    if (mu * PetscAbsReal(W[1]) < W[0]) {
      nunique++;
      worst_dr = PetscMax(worst_dr, (PetscAbsReal(r[0] - rs[0]) + PetscAbsReal(r[1] - rs[1])) / rs[0]);
    }
  }
  PetscCall(Check((PetscBool)(nviol == 0), "stick/slip boundary, 30000 cases: law satisfied to 1e-12 (worst)", worst, 1e-12));
  PetscCall(Checkf((PetscBool)(nunique > 0 && worst_dr < 1e-10), worst_dr, 0,
                   "stick/slip boundary: the %" PetscInt_FMT " unique solutions found (relative distance)", nunique));
  PetscFunctionReturn(0);
}

/* Normal-only contacts: r_n = max(0, -b_n / Wnn). */
static PetscErrorCode TestNormalOnly(void)
{
  unsigned long long seed  = 777;
  PetscReal          worst = 0.0;
  PetscInt           k, nstatus = 0, nviol = 0, nres = 0;

  PetscFunctionBeginUser;
  for (k = 0; k < 4000; k++) {
    PetscReal      W = PetscPowReal(10.0, Uniform(&seed, -3, 3)), b = Uniform(&seed, -1, 1), r, v, viol;
    KergsLawStatus st;

    st = KergsLawSolve(1, &W, &b, 0.0, PETSC_TRUE, &r);
    if (st != (b >= 0 ? KERGS_LAW_OPEN : KERGS_LAW_STICK)) nstatus++;
    viol = LawViolation(1, &W, &b, 0.0, st, &r);
    if (!(viol <= 1e-12)) nviol++;
    v = W * r + b;
    if (!(KergsLawNaturalResidual2(1, &r, &v, 0.0, 1.0 / W, PETSC_TRUE) <= 1e-24 * (r * r + b * b / (W * W)))) nres++;
    worst = PetscMax(worst, viol);
  }
  {
    PetscReal      W = 2, b = -1, r = 3, rp = 0.7, vp = W * rp + b;
    KergsLawStatus st = KergsLawSolve(1, &W, &b, 0.0, PETSC_FALSE, &r);

    PetscReal res;

    PetscCall(
        Checkf((PetscBool)(st == KERGS_LAW_INACTIVE && r == 0), r, 0, "normal-only inactive: status inactive, r = 0 (status %d)", (int)st));
    /* at r_n = 0.7 (solution 0.5): residual |0.7 - max(0, 0.7 - 0.5 * 0.4)| = 0.2 */
    res = KergsLawNaturalResidual2(1, &rp, &vp, 0.0, 0.5, PETSC_TRUE);
    PetscCall(Check((PetscBool)(PetscAbsReal(res - 0.04) < 1e-15), "normal-only: squared natural residual at a wrong r", res, 0.04));
  }
  PetscCall(
      Check((PetscBool)(nstatus == 0), "normal-only, 4000 cases: status open for b_n >= 0, stick otherwise (wrong ones)", nstatus, 0));
  PetscCall(Check((PetscBool)(nviol == 0), "normal-only: law satisfied to 1e-12 (worst)", worst, 1e-12));
  PetscCall(Check((PetscBool)(nres == 0), "normal-only: natural residual zero at r (cases not)", nres, 0));
  PetscFunctionReturn(0);
}

/* Degenerate blocks (singular, zero, huge coupling): the answer stays finite and in the cone. */
static PetscErrorCode TestDegenerate(void)
{
  const PetscReal Ws[4][4] = {{1, 1, 1, 1}, {0, 0, 0, 0}, {1, 0, 0, 0}, {1e-300, 1, 1, 1e-300}};
  const PetscReal bs[3][2] = {{-1, 0.5}, {-1, -0.5}, {-1, 0.0}};
  const PetscReal mus[3]   = {0.0, 0.5, 5.0};
  PetscInt        i, j, k, nonfinite = 0, outside = 0;

  PetscFunctionBeginUser;
  for (i = 0; i < 4; i++)
    for (j = 0; j < 3; j++)
      for (k = 0; k < 3; k++) {
        PetscReal r[2];

        (void)KergsLawSolve(2, Ws[i], bs[j], mus[k], PETSC_TRUE, r);
        if (PetscIsInfOrNanReal(r[0]) || PetscIsInfOrNanReal(r[1]))
          nonfinite++;
        else if (!(r[0] >= 0 && PetscAbsReal(r[1]) <= mus[k] * r[0] * (1 + 1e-14)))
          outside++;
      }
  PetscCall(Check((PetscBool)(nonfinite == 0), "degenerate blocks, 36 cases: non-finite r", nonfinite, 0));
  PetscCall(Check((PetscBool)(outside == 0), "degenerate blocks: r outside the Coulomb cone", outside, 0));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(TestHandCases());
  PetscCall(TestRandom2D());
  PetscCall(TestBoundary2D());
  PetscCall(TestNormalOnly());
  PetscCall(TestDegenerate());
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
