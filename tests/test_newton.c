/* Solver type "newton" (src/solver/solvers/newton.c): the Alart-Curnier function's generalized Jacobian against
   finite differences away from the kinks, one-contact cases solved in at most 3 Newton steps, the wedged pair whose W
   is singular, the frictionless confine500 against the unilateral predictor's exact solution, 1 against n ranks, and a
   case where the line search is needed (a full Newton step increases the merit) and is taken. */
static const char help[] = "kergs newton solver tests.\n";

#include "testing.h"
#include <unistd.h>

/* ------------------------------------------------------------------------------------------------ */
/* The Alart-Curnier function and its Jacobian (KergsLawAlartCurnier)                               */

/* The piece of F a point (r, u) lies on, and how far from its boundaries (xi = 0, |z| = tau). */
static void Piece(PetscInt nc, const PetscScalar r[], const PetscScalar u[], PetscReal mu, PetscReal rho, PetscInt *piece,
                  PetscReal *margin)
{
  const PetscReal xi = PetscRealPart(r[0]) - rho * PetscRealPart(u[0]), tau = mu * PetscMax(xi, 0.0);
  const PetscReal z = nc > 1 ? PetscRealPart(r[1]) - rho * PetscRealPart(u[1]) : 0.0;

  *margin = PetscAbsReal(xi);
  if (xi <= 0)
    *piece = 0; /* open */
  else if (nc == 1)
    *piece = 1;
  else if (PetscAbsReal(z) < tau)
    *piece = 1; /* stick */
  else
    *piece = z > 0 ? 2 : 3; /* slip */
  if (nc > 1 && xi > 0) *margin = PetscMin(*margin, PetscAbsReal(PetscAbsReal(z) - tau));
}

/* A random contact: W_aa symmetric positive definite (L L^T + 0.1 I, L lower triangular; a positive scalar when nc = 1),
   mu in [0, 1) when frictional (0 otherwise), rho = 1 / W_nn. */
static PetscErrorCode RandomContact(PetscRandom rnd, PetscInt nc, PetscReal W[4], PetscReal *mu, PetscReal *rho)
{
  PetscReal L[3];

  PetscFunctionBeginUser;
  *mu = 0;
  for (PetscInt i = 0; i < 3; i++) PetscCall(PetscRandomGetValueReal(rnd, &L[i]));
  W[0] = L[0] * L[0] + 0.1;
  W[1] = W[2] = L[0] * L[1];
  W[3]        = L[1] * L[1] + L[2] * L[2] + 0.1;
  if (nc == 1) W[0] = PetscAbsReal(L[0]) + 0.1;
  if (nc > 1) PetscCall(PetscRandomGetValueReal(rnd, mu));
  *mu  = PetscAbsReal(*mu);
  *rho = 1.0 / W[0];
  PetscFunctionReturn(0);
}

/* Random points of each piece, for a random symmetric positive definite W_aa: the Jacobian J = A + B W_aa times a
   random direction against the difference quotient of F, with a step small enough not to leave the piece. */
static PetscErrorCode TestJacobian(void)
{
  PetscRandom rnd;
  PetscInt    seen[2][4] = {{0}}, bad = 0, tried = 0;
  PetscReal   worst = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscRandomCreate(PETSC_COMM_SELF, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, -1.0, 1.0));
  for (PetscInt k = 0; k < 4000; k++) {
    const PetscInt nc = k % 2 ? 2 : 1;
    PetscReal      mu, rho, W[4], b[2], F0[2], F1[2], A[4], B[4], Jd[2], margin, h, err = 0, scale = 0;
    PetscScalar    r[2] = {0, 0}, u[2] = {0, 0}, rh[2], uh[2], d[2] = {0, 0};
    PetscInt       piece;
    PetscCall(RandomContact(rnd, nc, W, &mu, &rho));
    for (PetscInt c = 0; c < nc; c++) {
      PetscReal x;
      PetscCall(PetscRandomGetValueReal(rnd, &x));
      r[c] = x;
      PetscCall(PetscRandomGetValueReal(rnd, &b[c]));
      PetscCall(PetscRandomGetValueReal(rnd, &x));
      d[c] = x;
    }
    for (PetscInt c = 0; c < nc; c++) {
      u[c] = b[c];
      for (PetscInt e = 0; e < nc; e++) u[c] += W[c * nc + e] * PetscRealPart(r[e]);
    }
    Piece(nc, r, u, mu, rho, &piece, &margin);
    if (margin < 1e-3) continue; /* too close to a kink for a difference quotient */
    tried++;
    seen[nc - 1][piece]++;
    KergsLawAlartCurnier(nc, r, u, mu, rho, PETSC_TRUE, F0, A, B);
    h = 1e-2 * margin / (1.0 + PetscAbsReal(W[0]) + PetscAbsReal(W[3])); /* F is linear on the piece: no truncation error */
    for (PetscInt c = 0; c < nc; c++) rh[c] = r[c] + h * d[c];
    for (PetscInt c = 0; c < nc; c++) {
      uh[c] = b[c];
      for (PetscInt e = 0; e < nc; e++) uh[c] += W[c * nc + e] * PetscRealPart(rh[e]);
    }
    KergsLawAlartCurnier(nc, rh, uh, mu, rho, PETSC_TRUE, F1, NULL, NULL);
    for (PetscInt c = 0; c < nc; c++) { /* J d = A d + B W d */
      Jd[c] = 0;
      for (PetscInt e = 0; e < nc; e++) {
        PetscReal Wd = 0;
        for (PetscInt f = 0; f < nc; f++) Wd += W[e * nc + f] * PetscRealPart(d[f]);
        Jd[c] += A[c * nc + e] * PetscRealPart(d[e]) + B[c * nc + e] * Wd;
      }
      err += PetscSqr((F1[c] - F0[c]) / h - Jd[c]);
      scale += PetscSqr(Jd[c]) + PetscSqr(PetscRealPart(d[c]));
    }
    err   = PetscSqrtReal(err / scale);
    worst = PetscMax(worst, err);
    if (err > 1e-6) bad++;
  }
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(
      Check((PetscBool)(bad == 0), "Alart-Curnier Jacobian = difference quotient away from the kinks (worst relative error)", worst, 1e-6));
  PetscCall(Check((PetscBool)(seen[0][0] > 100 && seen[0][1] > 100), "... frictionless: open and closed points both tried",
                  PetscMin(seen[0][0], seen[0][1]), 100));
  PetscCall(Check((PetscBool)(seen[1][0] > 50 && seen[1][1] > 50 && seen[1][2] > 50 && seen[1][3] > 50),
                  "... frictional: open, stick, slip+ and slip- points all tried",
                  PetscMin(PetscMin(seen[1][0], seen[1][1]), PetscMin(seen[1][2], seen[1][3])), 50));
  {
    PetscScalar r[2] = {0.3, -0.1}, u[2] = {1, 2};
    PetscReal   F[2], A[4], B[4];
    KergsLawAlartCurnier(2, r, u, 0.5, 1.0, PETSC_FALSE, F, A, B);
    PetscCall(Check((PetscBool)(F[0] == 0.3 && F[1] == -0.1 && A[0] == 1 && A[3] == 1 && A[1] == 0 && B[0] == 0 && B[3] == 0),
                    "inactive contact: F = r, J = I", F[0], 0.3));
  }
  (void)tried;
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Whole steps                                                                                      */

#define ONE_DISK "-gravity 0,-10 -dt 1e-3 -disks_source list -disks_radius 0.1 -alert 0.01 -solver_type newton -solver_tol 1e-12 "

/* The smoothed Alart-Curnier function (KergsLawAlartCurnierSmoothed): at random points of every piece and at random
   eps, its Jacobian A + B W against central differences (it is smooth: no kink to avoid), and its distance to the
   nonsmooth function at most a small multiple of eps (every smoothed max is within eps of max). */
static PetscErrorCode TestSmoothedLaw(void)
{
  PetscRandom rnd;
  PetscReal   worst = 0, gap = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscRandomCreate(PETSC_COMM_SELF, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, -1.0, 1.0));
  for (PetscInt k = 0; k < 2000; k++) {
    const PetscInt  nc = k % 2 ? 2 : 1;
    PetscReal       mu, eps, rho, W[4], F0[2], Fp[2], Fm[2], Fns[2], A[4], B[4], err = 0, scale = 0;
    PetscScalar     r[2] = {0, 0}, u[2] = {0, 0}, rp[2], rm[2], up[2], um[2], d[2] = {0, 0}, b[2] = {0, 0};
    const PetscReal h = 1e-5; /* d of order 1: rounding stays far below the tolerance, truncation (h^2) too */
    PetscCall(RandomContact(rnd, nc, W, &mu, &rho));
    PetscCall(PetscRandomGetValueReal(rnd, &eps));
    eps = 1e-3 + 0.1 * PetscAbsReal(eps);
    for (PetscInt c = 0; c < nc; c++) {
      PetscReal x;
      PetscCall(PetscRandomGetValueReal(rnd, &x));
      r[c] = x;
      PetscCall(PetscRandomGetValueReal(rnd, &x));
      b[c] = x;
      PetscCall(PetscRandomGetValueReal(rnd, &x));
      d[c] = x;
    }
    for (PetscInt c = 0; c < nc; c++) {
      rp[c] = r[c] + h * d[c];
      rm[c] = r[c] - h * d[c];
      u[c] = up[c] = um[c] = b[c];
      for (PetscInt e = 0; e < nc; e++) {
        u[c] += W[c * nc + e] * PetscRealPart(r[e]);
        up[c] += W[c * nc + e] * PetscRealPart(r[e] + h * d[e]);
        um[c] += W[c * nc + e] * PetscRealPart(r[e] - h * d[e]);
      }
    }
    KergsLawAlartCurnierSmoothed(nc, r, u, mu, rho, PETSC_TRUE, eps, F0, A, B);
    KergsLawAlartCurnierSmoothed(nc, rp, up, mu, rho, PETSC_TRUE, eps, Fp, NULL, NULL);
    KergsLawAlartCurnierSmoothed(nc, rm, um, mu, rho, PETSC_TRUE, eps, Fm, NULL, NULL);
    KergsLawAlartCurnier(nc, r, u, mu, rho, PETSC_TRUE, Fns, NULL, NULL);
    for (PetscInt c = 0; c < nc; c++) {
      PetscReal Jd = 0;
      for (PetscInt e = 0; e < nc; e++) {
        PetscReal Wd = 0;
        for (PetscInt f = 0; f < nc; f++) Wd += W[e * nc + f] * PetscRealPart(d[f]);
        Jd += A[c * nc + e] * PetscRealPart(d[e]) + B[c * nc + e] * Wd;
      }
      err += PetscSqr((Fp[c] - Fm[c]) / (2 * h) - Jd);
      scale += PetscSqr(Jd) + PetscSqr(PetscRealPart(d[c]));
      gap = PetscMax(gap, PetscAbsReal(F0[c] - Fns[c]) / eps);
    }
    worst = PetscMax(worst, PetscSqrtReal(err / scale));
  }
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(Check((PetscBool)(worst <= 1e-6), "smoothed Alart-Curnier: Jacobian = central difference (worst relative error)", worst, 1e-6));
  PetscCall(Check((PetscBool)(gap <= 3.0), "smoothed Alart-Curnier: within a few eps of the nonsmooth function (worst |F_eps - F| / eps)",
                  gap, 3.0));
  PetscFunctionReturn(0);
}

/* One disk and one wall: open (moving away), resting (closing, stick), on a slope below and above tan = mu (stick,
   slip). Each step solved in at most 3 Newton steps, and the physics right. */
/* `extra`: options added to every case, named in the checks' labels. */
static PetscErrorCode TestOneContact(const char *extra)
{
  struct {
    const char *what, *opts;
  } cases[] = {
      {"one contact, open (the disk leaves the floor)",
       ONE_DISK "-friction 0.5 -disks_x 0,0.1 -disks_velocity 0,5 -walls floor -wall_floor_a -5,0 -wall_floor_b 5,0"},
      {"one contact, stick (the disk rests on the floor)",
       ONE_DISK "-friction 0.5 -disks_x 0,0.0999999 -walls floor -wall_floor_a -5,0 -wall_floor_b 5,0"},
      {"one contact, frictionless (the disk rests on the floor)",
       ONE_DISK "-friction 0 -disks_x 0,0.0999999 -walls floor -wall_floor_a -5,0 -wall_floor_b 5,0"},
      /* slopes through the origin at 0.3 and 0.7 rad (tan 0.31 and 0.84) with mu = 0.5, rotation locked: stick, slip */
      {"one contact, stick on a slope (tan 0.31 < mu 0.5)",
       ONE_DISK "-friction 0.5 -disks_lock_rotation -disks_x -0.029552,0.095534 -walls slope -wall_slope_a -9.553365,-2.955202 "
                "-wall_slope_b 9.553365,2.955202 -wall_slope_infinite"},
      {"one contact, slip on a slope (tan 0.84 > mu 0.5)",
       ONE_DISK "-friction 0.5 -disks_lock_rotation -disks_x -0.064422,0.076484 -walls slope -wall_slope_a -7.648422,-6.442177 "
                "-wall_slope_b 7.648422,6.442177 -wall_slope_infinite"},
  };

  PetscFunctionBeginUser;
  for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
    PetscInt     maxits = 0, nconv = 0;
    PetscReal    maxres, v[KERGS_DIM];
    KergsStepper st;
    char         opts[1024];
    PetscCall(PetscSNPrintf(opts, sizeof(opts), "%s -steps 5 %s", cases[i].opts, extra));
    PetscCall(RunSteps(opts, 5, &st, &maxits, &maxres, &nconv));
    PetscCall(Checkf((PetscBool)(maxits <= 3 && nconv == 5), maxits, 3, "%s%s%s: Newton steps per time step (all converged)", cases[i].what,
                     extra[0] ? ", " : "", extra));
    /* a loaded frictional contact: the start ran (the interior point's first point, r_n = rho |v^d_n| and r_t = 0, already
       solves the disk resting on the floor: no iteration there) */
    if ((strstr(extra, "desaxce") && (i == 1 || i == 3 || i == 4)) || (strstr(extra, "_ip_") && (i == 3 || i == 4))) {
      const char *stat = strstr(extra, "desaxce") ? "desaxce_qps" : "ip_iterations";
      PetscReal   sum  = 0, q;
      for (PetscInt row = 0; row < 5; row++) {
        PetscCall(StatAt(st->results, stat, row, &q));
        sum += q;
      }
      PetscCall(Checkf((PetscBool)(sum >= 1), sum, 1, "%s, %s: %s over the 5 steps", cases[i].what, extra, stat));
    }
    PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->v, KERGS_DIM, v));
    if (i == 1 || i == 2)
      PetscCall(
          Checkf((PetscBool)(PetscAbsReal(v[1]) < 1e-9 && PetscAbsReal(v[0]) < 1e-9), PetscAbsReal(v[1]), 0, "%s: at rest", cases[i].what));
    if (i == 3)
      PetscCall(Checkf((PetscBool)(PetscAbsReal(v[0]) + PetscAbsReal(v[1]) < 1e-9), PetscAbsReal(v[0]) + PetscAbsReal(v[1]), 0,
                       "%s: at rest", cases[i].what));
    if (i == 4) { /* slides down at g (sin - mu cos), 5 steps */
      const PetscReal a = 0.7, want = 10 * (PetscSinReal(a) - 0.5 * PetscCosReal(a)) * 5e-3,
                      got = -(v[0] * PetscCosReal(a) + v[1] * PetscSinReal(a));
      PetscCall(Checkf((PetscBool)(PetscAbsReal(got - want) < 1e-6 * want), got, want, "%s: slides at g(sin - mu cos)", cases[i].what));
    }
    PetscCall(KergsStepperDestroy(&st));
  }
  PetscFunctionReturn(0);
}

/* The De Saxce start (-solver_newton_desaxce_max_it) on cases/compact_small.h5 given friction 0.5 and stepped once at
   rest under its pressure walls (cases/rest_10k.opts on 300 disks): Newton alone needs about 120 Newton steps there
   (its merit's minima hold the contact states wrong), after the start's 3 convex QPs 6. Checked on this communicator
   (1 or 2 ranks): the step converges to 1e-8 in at most 10 Newton steps after 1 to 4 QPs (with the shift's sign
   flipped: 6 QPs and 13 Newton steps), and not in 60 Newton steps without the start. */
static PetscErrorCode TestDeSaxceStart(void)
{
  const char  *rest = "-options_file cases/rest_10k.opts -sample_input cases/compact_small.h5 -blowup_energy 0 -solver_tol 1e-8";
  char         opts[PETSC_MAX_PATH_LEN];
  PetscInt     maxits, nconv;
  PetscReal    maxres, qps;
  KergsStepper st;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts), "%s -solver_newton_desaxce_max_it 6", rest));
  PetscCall(RunSteps(opts, 1, &st, &maxits, &maxres, &nconv));
  PetscCall(StatAt(st->results, "desaxce_qps", -1, &qps));
  PetscCall(KergsStepperDestroy(&st));
  PetscCall(Checkf((PetscBool)(qps >= 1 && qps <= 4 && nconv == 1 && maxres <= 1e-8 && maxits <= 10), maxits, 10,
                   "frictional packing at rest (300 disks), De Saxce start (%g QPs, residual %g): Newton steps", (double)qps,
                   (double)maxres));
  PetscCall(PetscSNPrintf(opts, sizeof(opts), "%s -solver_max_it 60", rest));
  PetscCall(RunSteps(opts, 1, NULL, &maxits, &maxres, &nconv));
  PetscCall(Checkf((PetscBool)(nconv == 0), maxres, 1e-8, "the same step without the start: not converged in 60 Newton steps (residual)"));
  PetscFunctionReturn(0);
}

/* The interior-point start (-solver_newton_ip_max_it) on the same step as TestDeSaxceStart: from zero impulses its
   iterates reach 4e-5 in 12 iterations, after which Newton needs 5 steps. Checked on this communicator (1 or 2 ranks;
   `extra` chooses the linear solver): 1 to 20 interior-point iterations, then convergence to 1e-8 in at most
   `max_newton` Newton steps (about 120 without the start), and the working set still leaves the open contacts out of J
   (the start drops their small impulses). With additive Schwarz the start solves J by MUMPS's LU, whose pivoting keeps
   the iterates on the path two more iterations (to 5.8e-6): Newton then needs 18 steps. */
static PetscErrorCode TestInteriorPointStart(const char *extra, PetscInt max_newton)
{
  char         opts[PETSC_MAX_PATH_LEN];
  PetscInt     maxits, nconv;
  PetscReal    maxres, its, deferred;
  KergsStepper st;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts),
                          "-options_file cases/rest_10k.opts -sample_input cases/compact_small.h5 -blowup_energy 0 -solver_tol 1e-8 "
                          "-solver_newton_ip_max_it 30 %s",
                          extra));
  PetscCall(RunSteps(opts, 1, &st, &maxits, &maxres, &nconv));
  PetscCall(StatAt(st->results, "ip_iterations", -1, &its));
  PetscCall(StatAt(st->results, "deferred_contacts", -1, &deferred));
  PetscCall(KergsStepperDestroy(&st));
  PetscCall(Checkf((PetscBool)(its >= 1 && its <= 20 && nconv == 1 && maxres <= 1e-8 && maxits <= max_newton), maxits, max_newton,
                   "frictional packing at rest (300 disks), interior-point start%s%s (%g iterations, residual %g): Newton steps",
                   extra[0] ? ", " : "", extra, (double)its, (double)maxres));
  PetscCall(Checkf((PetscBool)(deferred > 0), deferred, 1, "... contacts left out of J after the start"));
  PetscFunctionReturn(0);
}

/* The interior-point start without friction (one component per contact: the LCP of the normal impulses) on the same
   300-disk step with -friction 0: newton alone takes 18 Newton steps; from the start's 13 iterations (to -solver_tol,
   without friction, unless -solver_newton_ip_tol is given) it takes 3, and with -solver_newton_ip_tol 1e-5 the start
   stops after 11. Checked on this communicator (`extra` chooses the linear solver): these figures, the answer to 1e-8,
   and the working set still leaving the open contacts out of J after the start (106 of them). */
static PetscErrorCode TestInteriorPointFrictionless(const char *extra)
{
  char         opts[PETSC_MAX_PATH_LEN];
  PetscInt     alone, maxits, nconv;
  PetscReal    maxres, its, its_given, deferred;
  KergsStepper st;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts),
                          "-options_file cases/rest_10k.opts -sample_input cases/compact_small.h5 -blowup_energy 0 -friction 0 "
                          "-solver_tol 1e-8 %s",
                          extra));
  PetscCall(RunSteps(opts, 1, NULL, &alone, &maxres, &nconv));
  PetscCall(Checkf((PetscBool)(nconv == 1 && alone >= 12), alone, 12,
                   "frictionless packing at rest (300 disks)%s%s, newton alone: Newton steps", extra[0] ? ", " : "", extra));
  PetscCall(PetscStrlcat(opts, " -solver_newton_ip_max_it 30", sizeof(opts)));
  PetscCall(RunSteps(opts, 1, &st, &maxits, &maxres, &nconv));
  PetscCall(StatAt(st->results, "ip_iterations", -1, &its));
  PetscCall(StatAt(st->results, "deferred_contacts", -1, &deferred));
  PetscCall(KergsStepperDestroy(&st));
  PetscCall(Checkf((PetscBool)(its >= 1 && its <= 20 && nconv == 1 && maxres <= 1e-8 && maxits <= 6), maxits, 6,
                   "frictionless packing at rest (300 disks), interior-point start%s%s (%g iterations, residual %g): Newton steps",
                   extra[0] ? ", " : "", extra, (double)its, (double)maxres));
  PetscCall(Checkf((PetscBool)(deferred > 0), deferred, 1, "... contacts left out of J after the frictionless start"));
  PetscCall(PetscStrlcat(opts, " -solver_newton_ip_tol 1e-5", sizeof(opts)));
  PetscCall(RunSteps(opts, 1, &st, &maxits, &maxres, &nconv));
  PetscCall(StatAt(st->results, "ip_iterations", -1, &its_given));
  PetscCall(KergsStepperDestroy(&st));
  PetscCall(Checkf((PetscBool)(its_given < its), its_given, its, "... with -solver_newton_ip_tol 1e-5 given, the start's iterations"));
  PetscFunctionReturn(0);
}

/* The 500-disk deposit pushed by a free wall (scripts/dem_compare --scene pressure) at dt 5.5e-3, with the
   interior-point start. */
#define PRESSURE_SCENE                                                                                                                     \
  "-options_file cases/confine500.opts -sample_input cases/deposit500.h5 -wall_box_right_velocity 0,0 -wall_box_right_type free "          \
  "-wall_box_right_mass 1 -wall_box_right_force -20,0 -materials 2 -friction 0.3 -friction_pairs 0,1,0 -wall_box_right_material 1 "        \
  "-dt 5.5e-3 -gap_rule predictive -solver_tol 1e-6 -solver_newton_ip_max_it 40"

/* The interior-point start leaves out of its problem the contacts that the warm start leaves open, and brings in those
   its iterates close. The 500-disk deposit pushed by a free wall (scripts/dem_compare --scene pressure) at dt 5.5e-3,
   first step from zero impulses: 183 of the 1,034 contacts within the alert distance start left out and 146 of them join
   (128 at the first iteration). The start followed by one Newton step reaches 3.8e-5; without the joins the start stalls
   at 9.7e-4, where the contacts left out are closing. With `extra` -solver_newton_redundant_max 0 on 2 ranks the start
   solves by MUMPS, whose solver is created again as J grows. */
static PetscErrorCode TestInteriorPointJoins(const char *extra)
{
  char      opts[PETSC_MAX_PATH_LEN];
  PetscInt  maxits, nconv;
  PetscReal maxres;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts), PRESSURE_SCENE " -solver_max_it 1 %s", extra));
  PetscCall(RunSteps(opts, 1, NULL, &maxits, &maxres, &nconv));
  PetscCall(Checkf((PetscBool)(maxres <= 2e-4), maxres, 2e-4,
                   "pressure scene at dt 5.5e-3, interior-point start%s%s and one Newton step: natural residual", extra[0] ? ", " : "",
                   extra));
  PetscFunctionReturn(0);
}

/* The wedged pair between static walls (a feasible problem, unlike cases/two_disks_wedged.opts whose squeezing wall
   makes it infeasible): 4 contacts, 6 DOFs, W singular. Every step converges. */
static PetscErrorCode TestWedged(void)
{
  PetscInt  maxits, nconv;
  PetscReal maxres;

  PetscFunctionBeginUser;
  PetscCall(RunSteps("-options_file cases/two_disks_wedged.opts -wall_right_velocity 0,0 -steps 20 -solver_type newton -solver_tol 1e-12",
                     20, NULL, &maxits, &maxres, &nconv));
  PetscCall(Check((PetscBool)(nconv == 20 && maxres <= 1e-12), "wedged pair, singular W: every step converges to 1e-12 (largest residual)",
                  maxres, 1e-12));
  PetscFunctionReturn(0);
}

/* Frictionless confine500, one step: the velocities (unique without friction, whatever the kernel part of r) of
   newton's impulses against those of the unilateral predictor, which solves the frictionless problem exactly by NLGS
   on the normal components (to -predictor_unilateral_tol). */
static PetscErrorCode TestFrictionless(void)
{
  KergsStepper   st;
  KergsPredictor p;
  PetscInt       maxits, nconv;
  PetscReal      maxres, diff, scale;
  Vec            rt, v1, v2, vd;
  Mat            W;

  PetscFunctionBeginUser;
  PetscCall(RunSteps("-options_file cases/confine500.opts -friction 0 -steps 1 -keep_H -solver_type newton -solver_tol 1e-12", 1, &st,
                     &maxits, &maxres, &nconv));
  PetscCall(Check((PetscBool)(nconv == 1), "frictionless confine500: newton converged to 1e-12", maxres, 1e-12));
  PetscCall(KergsOperatorsGetContactVectors(st->ops, NULL, NULL, &vd));
  PetscCall(KergsOperatorsGetW(st->ops, &W, NULL));
  PetscCall(VecDuplicate(vd, &rt));
  PetscCall(VecDuplicate(vd, &v1));
  PetscCall(VecDuplicate(vd, &v2));
  PetscCall(MatMultAdd(W, st->ops->r, vd, v1));
  PetscCall(PetscOptionsSetValue(NULL, "-predictor_unilateral_tol", "1e-14"));
  PetscCall(PetscOptionsSetValue(NULL, "-predictor_unilateral_max_it", "200000"));
  PetscCall(KergsPredictorCreate(PETSC_COMM_WORLD, &p));
  PetscCall(KergsPredictorSetType(p, KERGS_PREDICTOR_UNILATERAL));
  PetscCall(KergsPredictorSetFromOptions(p));
  PetscCall(KergsPredictorPredict(p, st->scene, st->contacts, st->ops, st->solver->active, rt));
  PetscCall(MatMultAdd(W, rt, vd, v2));
  PetscCall(VecNorm(v1, NORM_INFINITY, &scale));
  PetscCall(VecAXPY(v2, -1.0, v1));
  PetscCall(VecNorm(v2, NORM_INFINITY, &diff));
  PetscCall(Check((PetscBool)(diff <= 1e-8 * scale),
                  "frictionless confine500: velocities of newton = those of the unilateral predictor (relative)", diff / scale, 1e-8));
  PetscCall(KergsPredictorDestroy(&p));
  PetscCall(VecDestroy(&rt));
  PetscCall(VecDestroy(&v1));
  PetscCall(VecDestroy(&v2));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* The smoothing phase's raise of eps (-solver_newton_smoothing_raises): on confine500's cold first step the phase stalls
   at eps 4e-7 and a residual of 2e-3 (measured); raising eps a hundredfold and going on takes the step to 1e-10 in
   fewer Newton steps than handing over to the proximal iterations there (136 against 191). */
static PetscErrorCode TestSmoothingRaise(void)
{
  PetscInt  its[2], nconv[2];
  PetscReal maxres[2];

  PetscFunctionBeginUser;
  PetscCall(RunSteps("-options_file cases/confine500.opts -steps 1 -solver_type newton -solver_tol 1e-10", 1, NULL, &its[0], &maxres[0],
                     &nconv[0]));
  PetscCall(RunSteps("-options_file cases/confine500.opts -steps 1 -solver_type newton -solver_tol 1e-10 -solver_newton_smoothing_raises 0",
                     1, NULL, &its[1], &maxres[1], &nconv[1]));
  PetscCall(Check((PetscBool)(nconv[0] == 1 && nconv[1] == 1), "confine500's first step converges with and without the raise of eps",
                  PetscMax(maxres[0], maxres[1]), 1e-10));
  PetscCall(Check((PetscBool)(its[0] < its[1]), "... in fewer Newton steps with it", its[0], its[1]));
  PetscFunctionReturn(0);
}

/* After the interior-point start the smoothing phase does not raise eps unless -solver_newton_smoothing_raises is given
   (SmoothingRaises in newton.c): the start's answer lies on the contacts' pieces, and a raised eps leaves it. On the
   pressure scene's first two steps the phase stalls once; with the option given it raises eps there (measured: that
   step then takes 64 Newton steps instead of 41). Counted by the statistic smoothing_raises. */
static PetscErrorCode RaisesAfterStart(const char *opts, PetscReal *raises, PetscInt *nconv)
{
  KergsStepper st;
  PetscInt     maxits;
  PetscReal    maxres;

  PetscFunctionBeginUser;
  *raises = 0.0;
  PetscCall(RunSteps(opts, 2, &st, &maxits, &maxres, nconv));
  for (PetscInt row = 0; row < 2; row++) {
    PetscReal v;
    PetscCall(StatAt(st->results, "smoothing_raises", row, &v));
    *raises += v;
  }
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestNoRaiseAfterStart(void)
{
  PetscReal raises[2];
  PetscInt  nconv[2];

  PetscFunctionBeginUser;
  PetscCall(RaisesAfterStart(PRESSURE_SCENE " -steps 2", &raises[0], &nconv[0]));
  PetscCall(RaisesAfterStart(PRESSURE_SCENE " -steps 2 -solver_newton_smoothing_raises 1", &raises[1], &nconv[1]));
  PetscCall(Check((PetscBool)(nconv[0] == 2 && nconv[1] == 2),
                  "pressure scene at dt 5.5e-3, interior-point start: both steps converge with and without the raise of eps",
                  PetscMin(nconv[0], nconv[1]), 2));
  PetscCall(Check((PetscBool)(raises[0] == 0), "... no raise of eps after the start by default", raises[0], 0));
  PetscCall(Check((PetscBool)(raises[1] >= 1), "... and a raise where the option is given (the phase stalls there)", raises[1], 1));
  PetscFunctionReturn(0);
}

/* The working set (-solver_newton_working_set), on a chain whose answer is known: disk A (radius 0.1, no gravity)
   hits B at 1 m/s; B is 1e-4 from C, which touches a wall. The warm start (r = 0) leaves B-C open, so it is left out
   of J; pushed by A, B closes B-C within the step (u_n = -0.5 + 1e-4 / dt < 0 once A and B share their momentum), so
   B-C leaves the open piece and is put back into J. The answer of the original problem under the predictive gap
   rule: B may close the gap and no more, so A and B move at 1e-4 / dt = 0.1 m/s, and C, against the wall, stays at
   rest. */
static PetscErrorCode TestWorkingSetChain(const char *linear)
{
  KergsStepper    st;
  PetscInt        maxits, nconv;
  PetscReal       maxres, v[3 * KERGS_DIM], grown, err = 0.0;
  char            opts[PETSC_MAX_PATH_LEN], label[256];
  const PetscReal want[3 * KERGS_DIM] = {0.1, 0, 0.1, 0, 0, 0};

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts),
                          "-gravity 0,0 -dt 1e-3 -friction 0.3 -disks_source list -disks_radius 0.1 -disks_x 0,0,0.2,0,0.4001,0 "
                          "-disks_velocity 1,0,0,0,0,0 -walls right -wall_right_a 0.5001,-1 -wall_right_b 0.5001,1 -alert 0.01 "
                          "-gap_rule predictive -solver_type newton -solver_tol 1e-12 -solver_newton_working_set -steps 1 %s",
                          linear));
  PetscCall(RunSteps(opts, 1, &st, &maxits, &maxres, &nconv));
  PetscCall(StatAt(st->results, "working_set_rebuilds", 0, &grown));
  PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->v, KERGS_DIM, v));
  for (PetscInt k = 0; k < 3 * KERGS_DIM; k++) err = PetscMax(err, PetscAbsReal(v[k] - want[k]));
  PetscCall(PetscSNPrintf(label, sizeof(label), "chain, working set%s: the step converges to 1e-12", linear[0] ? ", PETSc's LU on J" : ""));
  PetscCall(Check((PetscBool)(nconv == 1), label, maxres, 1e-12));
  PetscCall(Check((PetscBool)(grown >= 1), "... the contact B closes is put back into J (times J was set up again)", grown, 1));
  PetscCall(Check((PetscBool)(err < 1e-9), "... A and B at 1e-4 / dt, C at rest (largest velocity error)", err, 1e-9));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* Several ranks, the working set with friction under the predictive rule (confine500, 2 steps to 1e-10): every step
   converges, contacts are left out of J on some rank, and the velocities agree with one rank's to the tolerance's
   reach (with friction the answer is not unique: 1e-6, as TestPresorted). */
static PetscErrorCode TestWorkingSetRanks(void)
{
  const char  *opts = "-options_file cases/confine500.opts -gap_rule predictive -steps 2 -solver_type newton -solver_tol 1e-10";
  KergsStepper all, one;
  PetscInt     maxits, nconv;
  PetscReal    maxres, left_out, diff, scale;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper(opts, &all));
  PetscCall(StepAndSummarize(all, 2, &maxits, &maxres, &nconv));
  PetscCall(StatAt(all->results, "deferred_contacts", 1, &left_out));
  PetscCall(MakeStepperOn(PETSC_COMM_SELF, opts, &one));
  for (PetscInt s = 0; s < 2; s++) PetscCall(KergsStepperStep(one));
  PetscCall(VelocityDifference(all, one, &diff, &scale));
  PetscCall(CheckAll(PETSC_COMM_WORLD, (PetscBool)(nconv == 2),
                     "confine500 with friction, predictive, working set on every rank: 2 steps to 1e-10", maxres, 1e-10));
  PetscCall(CheckAll(PETSC_COMM_WORLD, (PetscBool)(left_out >= 100), "... contacts left out of J at the end of step 2", left_out, 100));
  PetscCall(CheckAll(PETSC_COMM_WORLD, (PetscBool)(diff <= 1e-6 * scale), "... velocities on every rank = on one rank (relative)",
                     diff / scale, 1e-6));
  PetscCall(KergsStepperDestroy(&all));
  PetscCall(KergsStepperDestroy(&one));
  PetscFunctionReturn(0);
}

/* Frictionless confine500 under the predictive gap rule (about a third of its contacts open), 2 steps to 1e-12 with
   and without the working set: both converge, contacts are deferred, and the velocities (unique without friction)
   agree. */
static PetscErrorCode TestWorkingSetConfine(void)
{
  KergsStepper st[2];
  PetscInt     maxits, nconv[2];
  PetscReal    maxres[2], deferred, diff, scale;

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < 2; k++) {
    char opts[PETSC_MAX_PATH_LEN];
    PetscCall(PetscSNPrintf(opts, sizeof(opts),
                            "-options_file cases/confine500.opts -friction 0 -gap_rule predictive -steps 2 -solver_type newton -solver_tol "
                            "1e-12 -solver_newton_working_set %s",
                            k == 0 ? "1" : "0"));
    PetscCall(RunSteps(opts, 2, &st[k], &maxits, &maxres[k], &nconv[k]));
  }
  PetscCall(StatAt(st[0]->results, "deferred_contacts", 1, &deferred));
  PetscCall(Check((PetscBool)(nconv[0] == 2 && nconv[1] == 2),
                  "frictionless confine500, predictive: 2 steps to 1e-12 with and without the working set", PetscMax(maxres[0], maxres[1]),
                  1e-12));
  PetscCall(Check((PetscBool)(deferred >= 100), "... contacts left out of J at the end of step 2", deferred, 100));
  PetscCall(VelocityDifference(st[0], st[1], &diff, &scale));
  PetscCall(Check((PetscBool)(diff <= 1e-8 * scale), "... the same velocities (relative)", diff / scale, 1e-8));
  for (PetscInt k = 0; k < 2; k++) PetscCall(KergsStepperDestroy(&st[k]));
  PetscFunctionReturn(0);
}

/* Whether the solver's view (ASCII only: written to a scratch file by the ranks of comm, read back by its first rank)
   contains `phrase`. */
static PetscErrorCode ViewSays(MPI_Comm comm, KergsSolver solver, const char *phrase, PetscBool *says)
{
  PetscViewer viewer;
  char        path[PETSC_MAX_PATH_LEN], text[16384] = "", *found = NULL;
  int         pid = (int)getpid();
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Bcast(&pid, 1, MPI_INT, 0, comm));
  PetscCall(PetscSNPrintf(path, sizeof(path), "/tmp/kergs-test-newton-view-%d.txt", pid));
  PetscCall(PetscViewerASCIIOpen(comm, path, &viewer));
  PetscCall(KergsSolverView(solver, viewer));
  PetscCall(PetscViewerDestroy(&viewer));
  if (rank == 0) {
    FILE  *fp = fopen(path, "r");
    size_t len;
    PetscCheck(fp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "cannot read back %s", path);
    len       = fread(text, 1, sizeof(text) - 1, fp);
    text[len] = 0;
    fclose(fp);
    remove(path);
    PetscCall(PetscStrstr(text, phrase, &found));
  }
  *says = (PetscBool)(found != NULL);
  PetscCallMPI(MPI_Bcast(says, 1, MPIU_BOOL, 0, comm));
  PetscFunctionReturn(0);
}

/* Whether the view says that J is stored in W's AMD order (PresortContacts in newton_linear.c). */
static PetscErrorCode ViewSaysPresorted(KergsSolver solver, PetscBool *presorted)
{
  PetscFunctionBeginUser;
  PetscCall(ViewSays(PETSC_COMM_SELF, solver, "J stored in W's AMD order", presorted));
  PetscFunctionReturn(0);
}

/* On one rank J is stored in W's AMD order and factored in that order (PresortContacts in newton_linear.c); with an ordering
   chosen by option, J stays in the contacts' order and PETSc's LU reorders it. confine500's first step to 1e-12 both
   ways, with or without friction: the views say which applies, and the contact velocities agree to `vtol` of their
   size (without friction they are unique, and the Newton steps are the same; with friction, rounding could lead the
   two runs along different paths, measured 136 Newton steps both and velocities within 1.4e-11). */
static PetscErrorCode TestPresorted(PetscBool frictionless, PetscReal vtol, const char *what)
{
  KergsStepper st[2];
  PetscInt     maxits[2], nconv;
  PetscReal    maxres, diff, scale;
  PetscBool    presorted[2];
  Vec          v[2], vd;
  Mat          W;
  char         opts[PETSC_MAX_PATH_LEN], label[256];

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < 2; k++) {
    PetscCall(PetscSNPrintf(
        opts, sizeof(opts), "-options_file cases/confine500.opts %s -steps 1 -keep_H -solver_type newton -solver_tol 1e-12 %s",
        frictionless ? "-friction 0 -solver_newton_cholesky 0" : "", k == 0 ? "" : "-solver_pc_factor_mat_ordering_type amd"));
    PetscCall(RunSteps(opts, 1, &st[k], &maxits[k], &maxres, &nconv));
    PetscCall(PetscSNPrintf(label, sizeof(label), "%s, J %s: converged to 1e-12", what, k == 0 ? "presorted" : "reordered by the LU"));
    PetscCall(Check((PetscBool)(nconv == 1), label, maxres, 1e-12));
    PetscCall(ViewSaysPresorted(st[k]->solver, &presorted[k]));
    PetscCall(KergsOperatorsGetContactVectors(st[k]->ops, NULL, NULL, &vd));
    PetscCall(KergsOperatorsGetW(st[k]->ops, &W, NULL));
    PetscCall(VecDuplicate(vd, &v[k]));
    PetscCall(MatMultAdd(W, st[k]->ops->r, vd, v[k]));
  }
  PetscCall(Check((PetscBool)(presorted[0] && !presorted[1]), "... the solver's view says which one was presorted", presorted[0], 1));
  if (frictionless) PetscCall(Check((PetscBool)(maxits[0] == maxits[1]), "... the same Newton steps", maxits[1], maxits[0]));
  PetscCall(VecNorm(v[0], NORM_INFINITY, &scale));
  PetscCall(VecAXPY(v[1], -1.0, v[0]));
  PetscCall(VecNorm(v[1], NORM_INFINITY, &diff));
  PetscCall(Check((PetscBool)(diff <= vtol * scale), "... the same contact velocities (relative)", diff / scale, vtol));
  for (PetscInt k = 0; k < 2; k++) {
    PetscCall(VecDestroy(&v[k]));
    PetscCall(KergsStepperDestroy(&st[k]));
  }
  PetscFunctionReturn(0);
}

/* Without friction on one rank, J's rows divided by B make it symmetric and CHOLMOD factors it (SymmetricRows in
   newton_linear.c); -solver_newton_cholesky 0 keeps PETSc's LU of J = A + B W. The frictionless packing at rest (300
   disks) from zero impulses to 1e-8, newton alone: the view says which ran, and both take the same Newton steps to
   the same contact velocities (unique without friction). Measured: 18 Newton steps both with the smoothing phase, 19
   without (`extra` -solver_newton_smoothing 0) and 19 without the working set, velocities within 2e-15 of their size. Without smoothing the
   Newton steps meet rows of contacts on the open piece that still carry an impulse, whose known d the symmetric form moves to the
   right-hand side: with that move left out, 26 Newton steps instead of 19. */
static PetscErrorCode TestCholesky(const char *extra)
{
  KergsStepper st[2];
  PetscInt     maxits[2], nconv[2];
  PetscReal    maxres[2], diff, scale;
  PetscBool    cholmod[2];
  Vec          v[2], vd;
  Mat          W;
  char         opts[PETSC_MAX_PATH_LEN];

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < 2; k++) {
    PetscCall(PetscSNPrintf(opts, sizeof(opts),
                            "-options_file cases/rest_10k.opts -sample_input cases/compact_small.h5 -blowup_energy 0 -friction 0 "
                            "-solver_tol 1e-8 -keep_H -solver_newton_cholesky %s %s",
                            k == 0 ? "1" : "0", extra));
    PetscCall(RunSteps(opts, 1, &st[k], &maxits[k], &maxres[k], &nconv[k]));
    PetscCall(ViewSays(PETSC_COMM_SELF, st[k]->solver, "in the last step: PC cholesky, package cholmod", &cholmod[k]));
    PetscCall(KergsOperatorsGetContactVectors(st[k]->ops, NULL, NULL, &vd));
    PetscCall(KergsOperatorsGetW(st[k]->ops, &W, NULL));
    PetscCall(VecDuplicate(vd, &v[k]));
    PetscCall(MatMultAdd(W, st[k]->ops->r, vd, v[k]));
  }
  PetscCall(Checkf((PetscBool)(nconv[0] == 1 && maxres[0] <= 1e-8 && nconv[1] == 1 && maxres[1] <= 1e-8), maxres[0], 1e-8,
                   "frictionless packing at rest (300 disks)%s%s, J symmetric and factored by Cholesky, and by LU: converged to 1e-8",
                   extra[0] ? ", " : "", extra));
  PetscCall(Check((PetscBool)(cholmod[0] && !cholmod[1]), "... the view says CHOLMOD factored J, and not with -solver_newton_cholesky 0",
                  cholmod[0], 1));
  PetscCall(Check((PetscBool)(maxits[0] == maxits[1]), "... the same Newton steps as PETSc's LU of A + B W", maxits[0], maxits[1]));
  PetscCall(VecNorm(v[1], NORM_INFINITY, &scale));
  PetscCall(VecAXPY(v[0], -1.0, v[1]));
  PetscCall(VecNorm(v[0], NORM_INFINITY, &diff));
  PetscCall(Check((PetscBool)(diff <= 1e-8 * scale), "... the same contact velocities (relative)", diff / scale, 1e-8));
  for (PetscInt k = 0; k < 2; k++) {
    PetscCall(VecDestroy(&v[k]));
    PetscCall(KergsStepperDestroy(&st[k]));
  }
  PetscFunctionReturn(0);
}

/* The solver's options read again between two steps (KergsSolverSetFromOptions, public), newton being the default type
   (a -solver_type given makes the solver anew): the Cholesky that kergs chose for the last step's symmetric J is still
   kergs's own factorization, so the next step's J is built in the symmetric form for it. (Taken for the user's choice,
   J was built as A + B W and CHOLMOD factored one triangle of it.) The 300-disk compaction, frictionless, to 1e-8:
   100 steps (measured 19 Newton steps at step 100, 259 contacts), the options read again, one step. */
static PetscErrorCode TestCholeskyOptionsReadAgain(void)
{
  KergsStepper st;
  PetscInt     maxits, nconv;
  PetscReal    maxres, res, conv, its;
  PetscBool    cholmod;

  PetscFunctionBeginUser;
  PetscCall(RunSteps("-options_file cases/compact_small.opts -solver_tol 1e-8", 100, &st, &maxits, &maxres, &nconv));
  PetscCall(KergsSolverSetFromOptions(st->solver));
  PetscCall(KergsStepperStep(st));
  PetscCall(StatAt(st->results, "residual", -1, &res));
  PetscCall(StatAt(st->results, "converged", -1, &conv));
  PetscCall(StatAt(st->results, "iterations", -1, &its));
  PetscCall(ViewSays(PETSC_COMM_SELF, st->solver, "in the last step: PC cholesky, package cholmod", &cholmod));
  PetscCall(Checkf((PetscBool)(nconv == 100 && conv > 0.5 && res <= 1e-8 && its > 0 && cholmod), res, 1e-8,
                   "300-disk compaction, the solver's options read again after step 100: step 101 in %g Newton steps by CHOLMOD on the "
                   "symmetric J, converged",
                   its));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* Frictionless confine500, 3 steps, on every rank of the world and on one rank: the disks' velocities agree grain by
   grain to the solver's tolerance. */
/* `linear`: the options of the linear solver on several ranks (J gathered whole, or GMRES with additive Schwarz). */
static PetscErrorCode TestRanks(const char *linear, const char *what)
{
  char         opts[PETSC_MAX_PATH_LEN], label[128];
  KergsStepper all, one;
  PetscReal    diff = 0, scale = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts),
                          "-options_file cases/confine500.opts -friction 0 -steps 3 -solver_type newton -solver_tol 1e-12 %s", linear));
  PetscCall(PetscSNPrintf(label, sizeof(label), "frictionless confine500, %s: velocities on every rank = on one rank (relative)", what));
  PetscCall(MakeStepper(opts, &all));
  for (PetscInt s = 0; s < 3; s++) PetscCall(KergsStepperStep(all));
  PetscCall(MakeStepperOn(PETSC_COMM_SELF, opts, &one));
  for (PetscInt s = 0; s < 3; s++) PetscCall(KergsStepperStep(one));
  PetscCall(VelocityDifference(all, one, &diff, &scale));
  PetscCall(CheckAll(PETSC_COMM_WORLD, (PetscBool)(diff <= 1e-8 * scale), label, diff / scale, 1e-8));
  PetscCall(KergsStepperDestroy(&all));
  PetscCall(KergsStepperDestroy(&one));
  PetscFunctionReturn(0);
}

/* Several ranks, additive Schwarz (J above -solver_newton_redundant_max 0 rows): `scene` (then `extra`) for `nsteps`
   steps as kergs sets it up, and with `option` `value`, given with the run's options, or once the stepper exists
   (`late`: an option of the subdomain solvers, read at the first Newton solve, after the stepper's options were
   checked). The view says `phrase` for the first run only, and both runs converge in the same Newton steps and GMRES
   iterations, to the same velocities (relative `veltol`): a wrong block, row, copy or permutation changes the
   preconditioner and the GMRES iterations at once. */
static PetscErrorCode CompareSchwarzVariants(const char *scene, const char *extra, PetscInt nsteps, const char *option, const char *value,
                                             PetscBool late, const char *phrase, const char *label, PetscReal veltol)
{
  KergsStepper st[2];
  PetscInt     maxits[2], nconv[2];
  PetscReal    maxres[2], linear[2] = {0, 0}, l, diff, scale;
  PetscBool    says[2];
  char         opts[PETSC_MAX_PATH_LEN];

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < 2; k++) {
    PetscCall(PetscSNPrintf(opts, sizeof(opts),
                            "%s -steps %" PetscInt_FMT " -solver_type newton -solver_tol 1e-10 -solver_newton_redundant_max 0 %s %s %s",
                            scene, nsteps, extra, k && !late ? option : "", k && !late ? value : ""));
    PetscCall(MakeStepper(opts, &st[k]));
    if (k && late) PetscCall(PetscOptionsSetValue(NULL, option, value));
    PetscCall(StepAndSummarize(st[k], nsteps, &maxits[k], &maxres[k], &nconv[k]));
    PetscCall(ViewSays(PETSC_COMM_WORLD, st[k]->solver, phrase, &says[k]));
    if (k && late) PetscCall(PetscOptionsClearValue(NULL, option));
    for (PetscInt s = 0; s < nsteps; s++) {
      PetscCall(StatAt(st[k]->results, "linear_iterations", s, &l));
      linear[k] += l;
    }
  }
  PetscCall(CheckAll(PETSC_COMM_WORLD, (PetscBool)(says[0] && !says[1]), label, says[0], 1));
  PetscCall(CheckAll(PETSC_COMM_WORLD, (PetscBool)(nconv[0] == nsteps && nconv[1] == nsteps && maxits[0] == maxits[1]),
                     "... every step converges both ways, in the same Newton steps", maxits[0], maxits[1]));
  PetscCall(CheckAll(PETSC_COMM_WORLD, (PetscBool)(linear[0] == linear[1]), "... the same GMRES iterations", linear[0], linear[1]));
  PetscCall(VelocityDifference(st[0], st[1], &diff, &scale));
  PetscCall(CheckAll(PETSC_COMM_WORLD, (PetscBool)(diff <= veltol * scale), "... the same velocities (relative)", diff / scale, veltol));
  for (PetscInt k = 0; k < 2; k++) PetscCall(KergsStepperDestroy(&st[k]));
  PetscFunctionReturn(0);
}

/* Each subdomain is copied into its AMD order and factored there (newton_subdomain.c), unless an ordering is chosen
   for the subdomains by option: the factors are the same (measured: bitwise). confine500 with friction has 2 x 2-block
   (BAIJ) subdomains; frictionless confine5, one component per contact (AIJ), whose rows of one pattern MatGetRowIJ
   merges when asked to compress them (a crash before the sorted LU read AIJ rows uncompressed). */
static PetscErrorCode TestSortedSubdomains(const char *scene, PetscInt nsteps, const char *what)
{
  char label[256];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(label, sizeof(label), "%s, additive Schwarz: the subdomain solver is the sorted LU (not with an ordering option)",
                          what));
  PetscCall(CompareSchwarzVariants(scene, "", nsteps, "-solver_sub_pc_factor_mat_ordering_type", "amd", PETSC_TRUE,
                                   "the subdomain copied into that order", label, 1e-10));
  PetscFunctionReturn(0);
}

/* Each subdomain's J is computed from W's subdomain, extracted once per J, and the A and B blocks of its rows
   (newton_subdomain.c), instead of extracted from J at every set-up (-solver_newton_subdomains_from_w 0). The
   arithmetic is J's own (NewtonJacobianBlock), so the subdomain matrices, hence the GMRES iterations, the Newton steps
   and the velocities, are the same (measured: bitwise). With the predictive gap rule the working set sets J up again
   within a step (9 times over confine500's first 2 steps), and the subdomains are built again with it; with -solver_prox
   kernel the factorization of J (sigma I) preconditions GMRES on J_P. The view's count of subdomains built through
   W's says the shell served (a silent fallback to extracting J would pass every other check). */
static PetscErrorCode TestSubdomainsFromW(const char *scene, const char *extra, PetscInt nsteps, const char *what)
{
  char label[256];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(label, sizeof(label), "%s, additive Schwarz: subdomains computed from W's (not with the option off)", what));
  PetscCall(CompareSchwarzVariants(scene, extra, nsteps, "-solver_newton_subdomains_from_w", "0", PETSC_FALSE,
                                   "subdomain matrices built through W's subdomain in the last solve", label, 1e-12));
  PetscFunctionReturn(0);
}

/* Several ranks, GMRES with additive Schwarz (J above -solver_newton_redundant_max 0 rows) whose subdomains are
   factored by ILU(0) instead of LU: on confine500's first step 152 linear solves fail (the ILU of a nearly singular J),
   and each failure only makes the outer iteration raise sigma, the later solves succeeding on the better conditioned J:
   the step converges to 1e-10. With few contacts changing piece, the solver keeps its preconditioner (statistic
   reused_factorizations > 0). */
static PetscErrorCode TestRecovery(void)
{
  KergsStepper st;
  PetscReal    res, conv, failed, reused;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper("-options_file cases/confine500.opts -steps 1 -solver_type newton -solver_tol 1e-10 -solver_newton_redundant_max 0",
                        &st));
  /* read by the subdomain solvers at the first Newton solve, after the stepper's options were checked */
  PetscCall(PetscOptionsSetValue(NULL, "-solver_sub_pc_type", "ilu"));
  PetscCall(KergsStepperStep(st));
  PetscCall(PetscOptionsClearValue(NULL, "-solver_sub_pc_type"));
  PetscCall(StatAt(st->results, "residual", 0, &res));
  PetscCall(StatAt(st->results, "converged", 0, &conv));
  PetscCall(StatAt(st->results, "failed_linear_solves", 0, &failed));
  PetscCall(StatAt(st->results, "reused_factorizations", 0, &reused));
  PetscCall(KergsStepperDestroy(&st));
  PetscCall(Check((PetscBool)(failed > 0), "additive Schwarz with ILU subdomains: some linear solves fail", failed, 1));
  PetscCall(Check((PetscBool)(conv > 0.5 && res <= 1e-10), "... and the step still converges (natural residual)", res, 1e-10));
  PetscCall(Check((PetscBool)(reused > 0), "... keeping the preconditioner over a few changed contacts (reused set-ups)", reused, 1));
  PetscFunctionReturn(0);
}

/* confine500's first 5 steps, with friction: some full Newton steps increase the merit and are cut by the line search
   (statistic backtracks > 0), and every step converges; without the line search (-solver_newton_max_backtracks 0, every
   full step taken) the same steps need more Newton steps or fail (measured: steps 3 and 4 stop at the cap of 500 with
   residuals 5e-4 and 9e-3; over 2 steps only, full steps happened to win on the cold first step, 57 against 136). */
static PetscErrorCode TestLineSearch(void)
{
  KergsStepper st;
  PetscInt     maxits, nconv, maxits0, nconv0;
  PetscReal    maxres, bt = 0, b, maxres0;

  PetscFunctionBeginUser;
  PetscCall(RunSteps("-options_file cases/confine500.opts -steps 5 -solver_type newton -solver_tol 1e-10 -solver_max_it 500", 5, &st,
                     &maxits, &maxres, &nconv));
  for (PetscInt s = 0; s < 5; s++) {
    PetscCall(StatAt(st->results, "backtracks", s, &b));
    bt += b;
  }
  PetscCall(KergsStepperDestroy(&st));
  PetscCall(Check((PetscBool)(bt > 0 && nconv == 5),
                  "confine500 (cold start): the line search cut some Newton steps (halvings), every step converged", bt, 1));
  PetscCall(RunSteps("-options_file cases/confine500.opts -steps 5 -solver_type newton -solver_tol 1e-10 -solver_max_it 500 "
                     "-solver_newton_max_backtracks 0",
                     5, NULL, &maxits0, &maxres0, &nconv0));
  PetscCall(Check((PetscBool)(nconv0 < 5 || maxits0 > maxits),
                  "... without it (full steps), fewer steps converge or they take more Newton steps", maxits0, maxits));
  PetscFunctionReturn(0);
}

/* -solver_prox kernel: the proximal term sigma P (r - r_c) on ker W alone (P through the kernel projector), its Newton
   systems solved by GMRES preconditioned by the factorization of the identity term's J. confine500's cold first step
   goes through proximal outer iterations (the smoothing phase stalls there, TestSmoothingRaise): both steps must reach
   1e-10, step 1 through more than one outer iteration and with GMRES iterations beyond one per Newton step (the kernel
   path ran: 579 for 134 Newton steps measured), in about the Newton steps of the identity term (136). */
static PetscErrorCode TestProxKernel(void)
{
  KergsStepper st;
  PetscInt     maxits, nconv;
  PetscReal    maxres, outer, its, linear;

  PetscFunctionBeginUser;
  PetscCall(RunSteps("-options_file cases/confine500.opts -steps 2 -solver_type newton -solver_prox kernel -solver_tol 1e-10 "
                     "-solver_max_it 1000",
                     2, &st, &maxits, &maxres, &nconv));
  PetscCall(Check((PetscBool)(nconv == 2 && maxres <= 1e-10), "confine500, -solver_prox kernel: 2 steps to 1e-10 (largest residual)",
                  maxres, 1e-10));
  PetscCall(StatAt(st->results, "outer_iterations", 0, &outer));
  PetscCall(StatAt(st->results, "iterations", 0, &its));
  PetscCall(StatAt(st->results, "linear_iterations", 0, &linear));
  PetscCall(Check((PetscBool)(outer > 1 && linear > 2 * its), "confine500, -solver_prox kernel: step 1's GMRES iterations per Newton step",
                  linear / its, 2));
  PetscCall(Check((PetscBool)(its <= 200), "confine500, -solver_prox kernel: step 1's Newton steps (identity: 136)", its, 200));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscMPIInt size;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  if (size == 1) {
    PetscCall(TestJacobian());
    PetscCall(TestSmoothedLaw());
    PetscCall(TestOneContact(""));
    PetscCall(TestOneContact("-solver_newton_working_set 0"));
    PetscCall(TestOneContact("-solver_newton_desaxce_max_it 4"));
    PetscCall(TestOneContact("-solver_newton_ip_max_it 30"));
    PetscCall(TestDeSaxceStart());
    PetscCall(TestInteriorPointStart("", 10));
    PetscCall(TestInteriorPointFrictionless(""));
    PetscCall(TestInteriorPointJoins(""));
    PetscCall(TestWorkingSetChain(""));
    PetscCall(TestWorkingSetChain("-solver_pc_type lu"));
    PetscCall(TestWorkingSetConfine());
    PetscCall(TestWedged());
    PetscCall(TestFrictionless());
    PetscCall(TestSmoothingRaise());
    PetscCall(TestNoRaiseAfterStart());
    PetscCall(TestPresorted(PETSC_TRUE, 1e-8, "frictionless confine500"));
    PetscCall(TestPresorted(PETSC_FALSE, 1e-6, "confine500 with friction"));
    PetscCall(TestCholesky(""));
    PetscCall(TestCholesky("-solver_newton_smoothing 0"));
    PetscCall(TestCholesky("-solver_newton_working_set 0")); /* every contact a row of J, in the contacts' order */
    PetscCall(TestCholeskyOptionsReadAgain());
    PetscCall(TestLineSearch());
    PetscCall(TestProxKernel());
  } else {
    PetscCall(TestRanks("", "J gathered on every rank"));
    PetscCall(TestRanks("-solver_newton_redundant_max 0", "GMRES with additive Schwarz"));
    PetscCall(TestRanks("-gap_rule predictive -solver_newton_working_set", "working set, J gathered"));
    PetscCall(TestRanks("-gap_rule predictive -solver_newton_working_set -solver_newton_redundant_max 0", "working set, additive Schwarz"));
    PetscCall(TestWorkingSetRanks());
    PetscCall(TestDeSaxceStart());
    PetscCall(TestInteriorPointStart("", 10));
    PetscCall(TestInteriorPointStart("-solver_newton_redundant_max 0", 25));
    PetscCall(TestInteriorPointFrictionless(""));
    PetscCall(TestInteriorPointFrictionless("-solver_newton_redundant_max 0"));
    PetscCall(TestInteriorPointJoins(""));
    PetscCall(TestInteriorPointJoins("-solver_newton_redundant_max 0"));
    PetscCall(TestRecovery());
    PetscCall(TestSortedSubdomains("-options_file cases/confine500.opts", 2, "confine500 with friction"));
    PetscCall(TestSortedSubdomains("-options_file cases/confine5.opts -friction 0", 3, "frictionless confine5"));
    PetscCall(TestSubdomainsFromW("-options_file cases/confine500.opts", "", 2, "confine500 with friction"));
    PetscCall(
        TestSubdomainsFromW("-options_file cases/confine500.opts", "-gap_rule predictive -solver_tol 1e-8", 2, "confine500, working set"));
    PetscCall(TestSubdomainsFromW("-options_file cases/confine5.opts -friction 0", "", 3, "frictionless confine5"));
    PetscCall(TestSubdomainsFromW("-options_file cases/confine5.opts", "-solver_prox kernel", 3, "confine5, kernel term"));
  }
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
