/* kergs solver type "newton": a semismooth Newton method on the Alart-Curnier function of the exact 2D law, inside
   proximal point iterations, solving the original per-step problem (not a regularised one) to tight tolerances
   (docs/solver.md, "Newton").

   Alart-Curnier function (KergsLawAlartCurnier, src/solver/law.c): per active contact, with u = W r + v^d and
   rho = -solver_newton_rho / W_aa,nn, F_n = r_n - max(0, xi), F_t = r_t - proj_[-tau, tau](r_t - rho u_t), xi = r_n - rho
   u_n, tau = mu max(0, xi); F = r for an inactive contact. F = 0 exactly when r solves the step's problem. F is
   piecewise linear, and an element of its generalized Jacobian is J = A + B W with A, B block diagonal (one ncomp x
   ncomp block per contact). W over the active contacts is stored whole (both triangles) and J is built on its pattern;
   J d = -F is solved through a KSP (prefix solver_; its set-up and solves are in newton_linear.c): a direct LU by default
   (PETSc's; without friction on one rank CHOLMOD's Cholesky of J's rows divided by B; on several ranks see
   ChooseLinearSolver there),
   any Krylov method and preconditioner by options.

   W is singular in a confined packing (its kernel: the self-equilibrated force networks), and so is J where stick
   contacts carry a hyperstatic network: plain Newton then stalls. The outer iterations solve, by Newton, the proximal
   problem with W + sigma I and v^d - sigma r_c around the current point r_c (-solver_prox identity; or W + sigma P and
   v^d - sigma P r_c with -solver_prox kernel, P the projector on ker W, its Newton systems by GMRES in newton_linear.c),
   whose Jacobian J = A + B (W + sigma I) is nonsingular; at the fixed point the proximal term vanishes, so the answer solves the
   original problem. sigma = alpha * natural residual * mean W_nn (within [sigma_min, sigma_max]) follows the residual
   down, so that the convergence is fast near the solution; alpha shrinks after a solved proximal problem and grows
   tenfold after a failed one (which restarts from the centre when it made things worse). The inner Newton steps are
   damped by an Armijo line search on 1/2 |F|^2. J is assembled and factored again only when the contact states or
   sigma changed. Before the proximal iterations, unless a plain attempt from the warm start (at most 3 Newton steps,
   stopped after one that gains less than tenfold) cuts the natural residual a thousandfold, a smoothing Newton phase
   (SolveSmoothed, -solver_newton_smoothing) solves the smoothed function (KergsLawAlartCurnierSmoothed) for eps
   falling tenfold at a time, with a Levenberg-Marquardt term in J, eps raised a hundredfold at its first stall (not
   after the interior-point start: SmoothingRaises); the proximal iterations finish from where it ends. A solve that
   stalls starts again from the same point with a smaller rho (SolverSolve_Newton, -solver_newton_second_rho). On one rank J is stored in
   W's AMD order (PresortContacts, newton_linear.c). The type is warm-started from the previous step's impulses like every type; optional
   NLGS sweeps first (-solver_newton_max_sweeps, -solver_newton_switch_tol), then an optional interior-point start
   (-solver_newton_ip_max_it, newton_ip.c) and De Saxce start (-solver_newton_desaxce_max_it, newton_desaxce.c). With
   -solver_newton_working_set, contacts that the warm start leaves open stay out of J while they are on the law's open piece
   (newton_working.c). Convergence is the natural residual of the original problem (-solver_tol, default 1e-10). */
#include "newton.h"

static const char *const NewtonProxes[] = {"none", "identity", "kernel", "NewtonProx", "NEWTON_PROX_", NULL};

/* ------------------------------------------------------------------------------------------------ */
/* The Alart-Curnier function over the local contacts (KergsLawAlartCurnier, src/solver/law.c)       */

/* F over the local contacts, from r and u; with the Jacobian blocks when jac. Returns 1/2 |F|^2 (global). */
static PetscErrorCode EvaluateFunction(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec F, PetscBool jac,
                                       PetscReal *merit)
{
  const PetscScalar *rl, *ul;
  PetscScalar       *Fl;
  PetscReal          sum = 0.0;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(u, &ul));
  PetscCall(VecGetArray(F, &Fl));
  for (PetscInt a = 0; a < n; a++) {
    PetscReal f[KERGS_MAXCOMP];
    /* a contact left out of J (working set) keeps the exact law: on its open piece its row stays the identity */
    if (nt->eps > 0 && !(nt->working_set && !nt->in_J[a]))
      KergsLawAlartCurnierSmoothed(nc, rl + a * nc, ul + a * nc, s->mu[a], nt->rho[a], s->active[a], nt->eps, f,
                                   jac ? nt->A + a * nc * nc : NULL, jac ? nt->B + a * nc * nc : NULL);
    else
      KergsLawAlartCurnier(nc, rl + a * nc, ul + a * nc, s->mu[a], nt->rho[a], s->active[a], f, jac ? nt->A + a * nc * nc : NULL,
                           jac ? nt->B + a * nc * nc : NULL);
    for (PetscInt c = 0; c < nc; c++) {
      Fl[a * nc + c] = f[c];
      sum += f[c] * f[c];
    }
  }
  PetscCall(VecRestoreArray(F, &Fl));
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sum, 1, MPIU_REAL, MPIU_SUM, s->comm));
  *merit = 0.5 * sum;
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Set-up and solve                                                                                 */

static PetscErrorCode EnsureWork(Newton *nt, PetscInt n)
{
  PetscFunctionBeginUser;
  if (n <= nt->nalloc) PetscFunctionReturn(0);
  PetscCall(PetscFree5(nt->A, nt->B, nt->rho, nt->rho_nat, nt->diagblock));
  PetscCall(PetscFree2(nt->Aused, nt->Bused));
  PetscCall(PetscFree2(nt->Afact, nt->Bfact));
  PetscCall(PetscFree(nt->in_J));
  nt->nalloc = PetscMax(n, 2 * nt->nalloc);
  PetscCall(PetscMalloc2(nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->Afact, nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->Bfact));
  PetscCall(PetscMalloc2(nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->Aused, nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->Bused));
  PetscCall(PetscMalloc5(nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->A, nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->B, nt->nalloc,
                         &nt->rho, nt->nalloc, &nt->rho_nat, nt->nalloc, &nt->diagblock));
  PetscCall(PetscMalloc1(nt->nalloc, &nt->in_J));
  PetscFunctionReturn(0);
}

static PetscErrorCode DestroyStepObjects(Newton *nt)
{
  PetscFunctionBeginUser;
  PetscCall(NewtonDestroyJacobian(nt));
  PetscCall(MatDestroy(&nt->Wfull));
  PetscCall(VecDestroy(&nt->F));
  PetscCall(VecDestroy(&nt->d));
  PetscCall(VecDestroy(&nt->Wd));
  PetscCall(VecDestroy(&nt->rtry));
  PetscCall(VecDestroy(&nt->utry));
  PetscCall(VecDestroy(&nt->Ftry));
  PetscCall(VecDestroy(&nt->rc));
  PetscCall(VecDestroy(&nt->ueff));
  PetscCall(VecDestroy(&nt->rplain));
  PetscCall(VecDestroy(&nt->rstart));
  PetscCall(VecDestroy(&nt->rbest));
  PetscFunctionReturn(0);
}

/* rho = factor / W_aa,nn on every local contact: the Alart-Curnier function of the attempts that follow. */
static void SetRho(Newton *nt, PetscInt n, PetscReal factor)
{
  nt->rho_used = factor;
  for (PetscInt a = 0; a < n; a++) nt->rho[a] = factor * nt->rho_nat[a];
}

static PetscErrorCode SolverSetUp_Newton(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  Newton        *nt = (Newton *)s->data;
  KergsDofLayout layout;
  PetscInt       n, nc;
  PetscReal     *blocks;
  Vec            r;

  PetscFunctionBeginUser;
  PetscCall(KergsSolverSetUpSweep(s, scene, contacts, ops)); /* active set, mu, and the residual's sweep on W */
  if (nt->prox == NEWTON_PROX_KERNEL) {                      /* P over the active contacts, for the proximal term sigma P (r - r_c) */
    PetscCall(KergsKernelSetActive(nt->kernel, s->active));
    PetscCall(KergsKernelSetUp(nt->kernel, scene, contacts, ops));
  }
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, NULL, NULL));
  nc = layout.ncomp;
  PetscCall(EnsureWork(nt, n));
  PetscCall(DestroyStepObjects(nt));
  PetscCall(KergsOperatorsGetFullW(ops, &nt->Wfull));
  if (!nt->working_set) PetscCall(NewtonSetUpJacobian(s, nt, n, nc)); /* else once the working set is chosen (SolverSolve_Newton) */
  PetscCall(PetscMalloc1(n * nc * nc + 1, &blocks));
  PetscCall(KergsSweepGetDiagonalBlocks(s->sweep, blocks));
  for (PetscInt a = 0; a < n; a++) {
    const PetscReal wnn = blocks[a * nc * nc];
    nt->rho_nat[a]      = wnn > 0 ? 1.0 / wnn : 1.0;
  }
  SetRho(nt, n, nt->rho_factor);
  PetscCall(PetscFree(blocks));
  PetscCall(VecDuplicate(r, &nt->F));
  PetscCall(VecDuplicate(r, &nt->d));
  PetscCall(VecDuplicate(r, &nt->Wd));
  PetscCall(VecDuplicate(r, &nt->rtry));
  PetscCall(VecDuplicate(r, &nt->utry));
  PetscCall(VecDuplicate(r, &nt->Ftry));
  PetscCall(VecDuplicate(r, &nt->rc));
  PetscCall(VecDuplicate(r, &nt->ueff));
  PetscCall(VecDuplicate(r, &nt->rplain));
  PetscCall(VecDuplicate(r, &nt->rstart));
  PetscCall(VecDuplicate(r, &nt->rbest));
  PetscFunctionReturn(0);
}

/* The velocity of the problem solved by the inner iterations: with the proximal term, (W + sigma I) r + v^d - sigma r_c,
   i.e. u + sigma (r - r_c) with u = W r + v^d. */
static PetscErrorCode ProximalVelocity(Newton *nt, Vec r, Vec u, Vec ueff)
{
  PetscFunctionBeginUser;
  PetscCall(VecCopy(u, ueff));
  if (nt->sigma > 0 && nt->prox == NEWTON_PROX_KERNEL) { /* u + sigma P (r - r_c) */
    PetscCall(VecWAXPY(nt->kx, -1.0, nt->rc, r));
    PetscCall(KergsKernelProject(nt->kernel, nt->kx, nt->kpx));
    PetscCall(VecAXPY(ueff, nt->sigma, nt->kpx));
  } else if (nt->sigma > 0) {
    PetscCall(VecAXPY(ueff, nt->sigma, r));
    PetscCall(VecAXPY(ueff, -nt->sigma, nt->rc));
  }
  PetscFunctionReturn(0);
}

/* r <- its projection on the Coulomb cones of the active contacts (r_n >= 0, |r_t| <= mu r_n); inactive ones to 0. */
static PetscErrorCode ProjectOnCones(KergsSolver s, PetscInt n, PetscInt nc, Vec r)
{
  PetscScalar *rl;

  PetscFunctionBeginUser;
  PetscCall(VecGetArray(r, &rl));
  for (PetscInt a = 0; a < n; a++) {
    PetscScalar *ra = rl + a * nc;
    if (!s->active[a]) {
      for (PetscInt c = 0; c < nc; c++) ra[c] = 0.0;
      continue;
    }
    if (nc == 1) {
      ra[0] = PetscMax(PetscRealPart(ra[0]), 0.0);
      continue;
    }
    {
      const PetscReal mu = s->mu[a], rn = PetscRealPart(ra[0]), rt = PetscRealPart(ra[1]), at = PetscAbsReal(rt);
      if (rn >= 0 && at <= mu * rn) continue;
      if (mu * at <= -rn)
        ra[0] = ra[1] = 0.0;
      else {
        const PetscReal pn = (rn + mu * at) / (1.0 + mu * mu);
        ra[0]              = pn;
        ra[1]              = rt >= 0 ? mu * pn : -mu * pn;
      }
    }
  }
  PetscCall(VecRestoreArray(r, &rl));
  PetscFunctionReturn(0);
}

/* Backtracking: the largest t = 2^-k (k <= -solver_newton_max_backtracks) with merit(r + t d) <= (1 - 2 armijo t)
   merit(r). Without such a t the smallest step is taken anyway and *ok is false: where a contact sits exactly on a
   kink of F (a grazing contact with r = 0 and u_n = 0, plenty after NLGS sweeps), the Newton direction need not
   decrease the merit, but a tiny step moves the contact off the kink and the next Jacobian is right. On exit r, u
   hold the new point. */
static PetscErrorCode LineSearch(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscReal *merit, PetscBool *ok)
{
  PetscReal t = 1.0, trial = 0.0;
  PetscInt  k;

  PetscFunctionBeginUser;
  if (!nt->project) PetscCall(MatMult(nt->Wfull, nt->d, nt->Wd));
  for (k = 0;; k++) {
    PetscCall(VecWAXPY(nt->rtry, t, nt->d, r));
    if (nt->project) { /* along the projected path r(t) = P_K(r + t d) */
      PetscCall(ProjectOnCones(s, n, nc, nt->rtry));
      PetscCall(MatMultAdd(nt->Wfull, nt->rtry, vd, nt->utry));
    } else
      PetscCall(VecWAXPY(nt->utry, t, nt->Wd, u));
    PetscCall(ProximalVelocity(nt, nt->rtry, nt->utry, nt->ueff));
    PetscCall(EvaluateFunction(s, nt, n, nc, nt->rtry, nt->ueff, nt->Ftry, PETSC_FALSE, &trial));
    if (trial <= (1.0 - 2.0 * nt->armijo * t) * *merit || k == nt->max_backtracks) break;
    t *= 0.5;
  }
  *ok = (PetscBool)(trial <= (1.0 - 2.0 * nt->armijo * t) * *merit);
  nt->backtracks += k;
  if (!*ok) nt->failed_searches++;
  PetscCall(VecCopy(nt->rtry, r));
  PetscCall(VecCopy(nt->utry, u));
  *merit = trial;
  PetscFunctionReturn(0);
}

/* r <- x and u = W r + v^d: a point the iterations move (back) to. */
static PetscErrorCode MoveTo(Newton *nt, Vec x, Vec r, Vec u, Vec vd)
{
  PetscFunctionBeginUser;
  PetscCall(VecCopy(x, r));
  PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
  PetscFunctionReturn(0);
}

/* At most `count` NLGS sweeps on W (the sweep of KergsSolverSetUpSweep), stopping early once the natural residual is
   at most `target`; u = W r + v^d and the residual on exit. */
static PetscErrorCode Sweeps(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscInt count, PetscReal target,
                             PetscReal *res)
{
  KergsSweepMeasures m;

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < count; k++) {
    PetscCall(KergsSweepRun(s->sweep, r, vd, NULL, NULL, &m));
    nt->sweeps++;
    if ((k + 1) % nt->sweep_check == 0 && k + 1 < count) {
      PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
      PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, res));
      if (*res <= target) break;
    }
  }
  PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
  PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, res));
  PetscFunctionReturn(0);
}

/* The monitors' line of a Newton step: the criterion of this type is the natural residual of the original problem,
   computed here only when a monitor is set (u = W r + v^d after the line search). */
static PetscErrorCode MonitorNewtonStep(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, PetscInt step)
{
  PetscReal res;

  PetscFunctionBeginUser;
  if (!s->nmonitors) PetscFunctionReturn(0);
  PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, &res));
  PetscCall(KergsSolverMonitor(s, step, res, res));
  PetscFunctionReturn(0);
}

/* With the working set: the contacts left out of J whose blocks left the law's open piece are put back, and J is set
   up again on its new rows (newton_working.c). In the smoothing phase their law becomes the smoothed one, so F, its
   blocks and *merit are evaluated again at r (u: the velocity the current F was evaluated with). */
static PetscErrorCode GrowWorkingSet(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, PetscReal *merit)
{
  PetscBool grown;

  PetscFunctionBeginUser;
  if (!nt->working_set) PetscFunctionReturn(0);
  PetscCall(NewtonWorkingSetGrow(s, nt, n, nc, &grown));
  if (!grown) PetscFunctionReturn(0);
  PetscCall(NewtonDestroyJacobian(nt));
  PetscCall(NewtonSetUpJacobian(s, nt, n, nc));
  if (nt->eps > 0) PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_TRUE, merit));
  PetscFunctionReturn(0);
}

/* Newton on the current (proximal) problem, from r: at most `count` steps, until |F| is at most `ftol`; *ok is false
   when some line search failed. Newton stops early when it crawls: -solver_newton_stall_steps steps in a row that
   each cut the merit by less than a tenth (many contacts change piece at every step, and the line search keeps
   them short); a larger proximal term is then cheaper than more steps. A `trial` (the plain attempt before the
   smoothing phase) also stops after a step that cut |F| by less than tenfold: the warm start is then not on the
   solution's piece, and the smoothing phase starts again from the warm start. */
static PetscErrorCode InnerNewton(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscInt count, PetscReal ftol,
                                  PetscBool trial, PetscInt *steps, PetscBool *ok)
{
  PetscReal merit;
  PetscBool decreased = PETSC_TRUE, solved, off_piece = PETSC_FALSE;
  PetscInt  crawling = 0;

  PetscFunctionBeginUser;
  *ok = PETSC_TRUE;
  PetscCall(ProximalVelocity(nt, r, u, nt->ueff));
  PetscCall(EvaluateFunction(s, nt, n, nc, r, nt->ueff, nt->F, PETSC_TRUE, &merit));
  for (PetscInt k = 0; k < count && PetscSqrtReal(2.0 * merit) > ftol; k++) {
    PetscCall(GrowWorkingSet(s, nt, n, nc, r, nt->ueff, &merit));
    /* with -solver_prox kernel, this J (sigma I) is the preconditioner of J_P (sigma P): NewtonSolveDirection */
    PetscCall(NewtonAssembleJacobian(s, nt, n, nc, nt->shift, nt->sigma));
    PetscCall(NewtonSolveDirection(nt, n, nc, &solved));
    if (!solved) {
      *ok   = PETSC_FALSE;
      merit = PETSC_MAX_REAL; /* not solved */
      break;
    }
    {
      PetscReal m0 = merit;
      PetscInt  b0 = nt->backtracks;
      PetscCall(LineSearch(s, nt, n, nc, r, u, vd, &merit, &decreased));
      PetscCall(PetscInfo(NULL, "inner %" PetscInt_FMT ": merit %g -> %g, %" PetscInt_FMT " halvings, decreased %d, sigma %g\n", k,
                          (double)m0, (double)merit, nt->backtracks - b0, (int)decreased, (double)nt->sigma));
      crawling  = merit > 0.81 * m0 ? crawling + 1 : 0;    /* |F| down by less than a tenth */
      off_piece = (PetscBool)(trial && merit > 0.01 * m0); /* |F| down by less than tenfold */
    }
    (*steps)++;
    PetscCall(MonitorNewtonStep(s, nt, n, nc, r, u, *steps));
    if (!decreased) *ok = PETSC_FALSE;
    if (off_piece) {
      *ok = PETSC_FALSE;
      break;
    }
    if (nt->stall_steps > 0 && crawling >= nt->stall_steps) {
      *ok = PETSC_FALSE;
      nt->stalls++;
      PetscCall(ProximalVelocity(nt, r, u, nt->ueff));
      PetscCall(EvaluateFunction(s, nt, n, nc, r, nt->ueff, nt->F, PETSC_FALSE, &merit));
      break;
    }
    PetscCall(ProximalVelocity(nt, r, u, nt->ueff));
    PetscCall(EvaluateFunction(s, nt, n, nc, r, nt->ueff, nt->F, PETSC_TRUE, &merit)); /* the Jacobian blocks at the new point */
  }
  nt->merit = merit;
  PetscFunctionReturn(0);
}

/* Mean W_nn over the active contacts: the scale of the proximal term. */
static PetscErrorCode MeanCompliance(KergsSolver s, Newton *nt, PetscInt n, PetscReal *mean)
{
  PetscReal sums[2] = {0.0, 0.0};

  PetscFunctionBeginUser;
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a]) {
      sums[0] += 1.0 / nt->rho_nat[a];
      sums[1] += 1.0;
    }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 2, MPIU_REAL, MPIU_SUM, s->comm));
  *mean = sums[1] > 0 ? sums[0] / sums[1] : 1.0;
  PetscFunctionReturn(0);
}

/* The largest |rho_a v^d_n,a| over the active contacts: the scale of an impulse, for the first eps. */
static PetscErrorCode ImpulseScale(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec vd, PetscReal *scale)
{
  const PetscScalar *v;

  PetscFunctionBeginUser;
  *scale = 0.0;
  PetscCall(VecGetArrayRead(vd, &v));
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a]) *scale = PetscMax(*scale, PetscAbsReal(nt->rho[a] * PetscRealPart(v[a * nc])));
  PetscCall(VecRestoreArrayRead(vd, &v));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, scale, 1, MPIU_REAL, MPIU_MAX, s->comm));
  PetscFunctionReturn(0);
}

/* The stalls of a smoothing phase that raise eps: -solver_newton_smoothing_raises, but none in a solve that goes on from
   the interior point's answer, unless the option was given. The raise is for a start whose contacts are still far from
   their pieces; the interior point's answer lies on them, and a raised eps leaves it (on a step of the 500-disk pressure
   scene of docs/tradeoff.md, from 3e-4 to 1.3e-3). Measured with the start on 24 variants of that scene (dt 5.5e-3; wall
   force, friction, -solver_newton_ip_max_it): 0.79 of the time, 24 unconverged steps against 44 (docs/solver.md). */
static PetscInt SmoothingRaises(const Newton *nt) { return nt->ip_answer && !nt->smooth_raises_set ? 0 : nt->smooth_raises; }

/* Smoothing Newton (-solver_newton_smoothing): Newton steps on the smoothed function F_eps (KergsLawAlartCurnierSmoothed),
   eps divided by 10 whenever F_eps is solved to a tenth of eps per component, each step damped by the Armijo line
   search on 1/2 |F_eps|^2. The first eps is -solver_newton_smoothing_eps times `scale` (ImpulseScale), at most ten
   times the start's |F| per component (a good start keeps a small eps); the last, 1e-12 of the first before that cap.
   The smoothing
   keeps J = A + B W nonsingular away from eps = 0 except on W's kernel where B is that of a stick contact; J's W part is
   regularised by sigma = kappa * natural residual * mean W_nn (within sigma_max; a Levenberg-Marquardt term: F keeps W,
   so the limit solves the original problem). Stops at the tolerance, at `limit` Newton steps in all, on a failed linear solve, or after
   -solver_newton_stall_steps steps in a row at one eps that each cut |F_eps| by less than a tenth (J nearly singular
   as eps -> 0): the proximal iterations go on from there. The first such stall of a solve (up to SmoothingRaises of
   them) instead raises eps a hundredfold and goes on from the current point: eps was lowered too early, while a few
   contacts were still far from their piece (on pressure20k's cold first step, two contacts closing at 5e-4 m/s with r_n = 0 held the
   residual at 1e-3), and the smoother function lets them move. */
static PetscErrorCode SolveSmoothed(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, PetscInt nglobal, Vec r, Vec u, Vec vd,
                                    PetscReal wmean, PetscReal scale, PetscInt limit, PetscInt *steps, PetscReal *res)
{
  PetscReal merit, m0, epsmin;
  PetscInt  stalls = 0, raises = 0;
  PetscBool ok, solved;

  PetscFunctionBeginUser;
  nt->sigma = 0.0; /* F without a proximal term (ProximalVelocity: u itself) */
  PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_FALSE, &merit));
  nt->eps = PetscMin(nt->smooth_eps * scale, 10.0 * PetscSqrtReal(2.0 * merit / (PetscReal)nglobal));
  epsmin  = 1e-12 * nt->smooth_eps * scale;
  while (*res > s->tol && *steps < limit && nt->eps > 0) {
    const PetscInt b0 = nt->backtracks;
    PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_TRUE, &merit));
    while (PetscSqrtReal(2.0 * merit) <= 0.1 * nt->eps * PetscSqrtReal((PetscReal)nglobal) && nt->eps > epsmin) {
      nt->eps *= 0.1;
      stalls = 0;
      PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_TRUE, &merit));
    }
    PetscCall(GrowWorkingSet(s, nt, n, nc, r, u, &merit));
    m0 = merit;
    PetscCall(NewtonAssembleJacobian(s, nt, n, nc, nt->shift, PetscMin(nt->smooth_kappa * *res, nt->sigma_max) * wmean));
    PetscCall(NewtonSolveDirection(nt, n, nc, &solved));
    if (!solved) break;
    PetscCall(LineSearch(s, nt, n, nc, r, u, vd, &merit, &ok));
    (*steps)++;
    nt->smooth_steps++;
    PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, res));
    PetscCall(MonitorNewtonStep(s, nt, n, nc, r, u, *steps));
    PetscCall(PetscInfo(NULL, "smoothing %" PetscInt_FMT ": natural residual %g, eps %g, %" PetscInt_FMT " halvings\n", *steps,
                        (double)*res, (double)nt->eps, nt->backtracks - b0));
    stalls = merit > 0.81 * m0 ? stalls + 1 : 0; /* |F_eps| down by less than a tenth */
    if (nt->stall_steps > 0 && stalls >= nt->stall_steps) {
      if (raises == SmoothingRaises(nt)) break;
      raises++;
      nt->smooth_raised++;
      stalls = 0;
      nt->eps *= 100.0;
      PetscCall(PetscInfo(NULL, "smoothing stalled: eps raised to %g\n", (double)nt->eps));
    }
  }
  nt->eps = 0.0;
  PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_FALSE, &nt->merit)); /* the exact law's merit, for the statistics */
  PetscFunctionReturn(0);
}

/* The natural map's projection p = r - e, taken when it lowers the natural residual. Newton reaches a solution whose
   impulses vanish (every contact separating) only asymptotically, and there the relative residual of any r != 0 is 1:
   measured on a wall hitting a lattice at 20 m/s, 2000 Newton steps ended at |r| ~ 1e-71 with residual 1, where the
   projection gives r = 0 exactly, residual 0. */
static PetscErrorCode Polish(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscReal *res)
{
  const PetscScalar *rl, *ul;
  PetscScalar       *pl;
  PetscReal          polished;

  PetscFunctionBeginUser;
  PetscCall(VecCopy(r, nt->rplain));
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(u, &ul));
  PetscCall(VecGetArray(nt->rc, &pl));
  for (PetscInt a = 0; a < n; a++) {
    PetscReal ra[KERGS_MAXCOMP], e[KERGS_MAXCOMP];
    NewtonContactNaturalMap(s, nt, nc, a, rl, ul, ra, e);
    for (PetscInt c = 0; c < nc; c++) pl[a * nc + c] = ra[c] - e[c];
  }
  PetscCall(VecRestoreArray(nt->rc, &pl));
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MoveTo(nt, nt->rc, r, u, vd));
  PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, &polished));
  if (polished < *res)
    *res = polished;
  else
    PetscCall(MoveTo(nt, nt->rplain, r, u, vd));
  PetscFunctionReturn(0);
}

/* One attempt from r: outer iterations, each solving, by at most -solver_prox_inner_max Newton steps, the proximal
   problem with W + sigma I (or W + sigma P) and v^d - sigma r_c around the current r_c = r, and moving r_c to its
   solution. The proximal term makes every inner Jacobian nonsingular (without it, -solver_prox none, J is singular
   where stick contacts carry a hyperstatic network); at the fixed point it vanishes, so r solves the original problem.
   The first outer iteration is plain Newton (sigma_min), kept only if it lowered the natural residual; with
   `smoothing`, the smoothing phase follows it unless it gained a thousandfold. Ends at the tolerance, once *steps
   reaches `limit`, or (window > 0) after an outer iteration that ends `window` Newton steps after the natural residual
   last gained tenfold, the smoothing phase included; *res_io is the natural residual on entry and on exit. */
static PetscErrorCode Attempt(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, PetscInt nglobal, Vec r, Vec u, Vec vd, PetscReal wmean,
                              PetscBool smoothing, PetscInt limit, PetscInt window, PetscInt *steps, PetscReal *res_io)
{
  PetscReal res = *res_io, alpha = nt->alpha, mark_res = *res_io;
  PetscInt  outer = 0, mark_step = *steps;
  PetscBool ok;

  PetscFunctionBeginUser;
  while (res > s->tol && nglobal > 0 && *steps < limit) {
    PetscReal before = res, inner_tol;
    PetscCall(VecCopy(r, nt->rc));
    PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, &res)); /* |e| at the centre (after a rejected outer iteration too) */
    /* the first attempt is plain Newton (the smallest sigma): enough when the warm start lies on the solution's piece
       of F, and the residual (absolute at r = 0) says little about the distance to the solution */
    nt->sigma = nt->prox != NEWTON_PROX_NONE
                    ? (outer == 0 ? nt->sigma_min : PetscClipInterval(alpha * res, nt->sigma_min, nt->sigma_max)) * wmean
                    : 0.0;
    /* |F| scales with rho where the natural residual's map uses 1 / W_nn: a smaller rho asks for a smaller |F| */
    inner_tol = nt->inner_rtol * PetscMin(1.0, nt->rho_used) * nt->enorm;
    {
      const PetscInt before_steps = *steps;
      /* with smoothing, the plain attempt gets 3 Newton steps: enough on the solution's piece (a few contacts); it
         stops after one that gained less than tenfold, as little as possible lost otherwise */
      const PetscBool plain = (PetscBool)(outer == 0 && smoothing);
      PetscCall(InnerNewton(s, nt, n, nc, r, u, vd, PetscMin(plain ? 3 : nt->inner_max, limit - *steps), inner_tol, plain, steps, &ok));
      if (*steps == before_steps) { /* an outer iteration without a Newton step still counts: the loop ends */
        (*steps)++;
        PetscCall(MonitorNewtonStep(s, nt, n, nc, r, u, *steps));
      }
    }
    PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, &res));
    outer++;
    nt->outer++;
    ok = (PetscBool)(PetscSqrtReal(2.0 * nt->merit) <= inner_tol); /* the proximal problem was solved */
    if (outer == 1 && nt->prox != NEWTON_PROX_NONE && res >= before) {
      /* plain Newton from the warm start went elsewhere (along W's near-kernel, where sigma_min barely holds it): back */
      PetscCall(MoveTo(nt, nt->rc, r, u, vd));
      res = before;
    } else if (ok)
      alpha = res < before ? PetscMax(alpha / 3.0, nt->alpha_min) : alpha; /* a proximal step: always taken */
    else if (res < 0.9 * before)
      alpha *= 10.0; /* progress, but the proximal problem was not solved: more damping */
    else {           /* no progress: more damping, from the centre */
      alpha *= 10.0;
      if (res >= before) {
        PetscCall(MoveTo(nt, nt->rc, r, u, vd));
        res = before;
      }
    }
    PetscCall(PetscInfo(NULL,
                        "outer %" PetscInt_FMT " (%" PetscInt_FMT " Newton steps): natural residual %g -> %g, inner solved %d, alpha %g\n",
                        nt->outer, *steps, (double)before, (double)res, (int)ok, (double)alpha));
    /* unless plain Newton gained three orders of magnitude (it is then on the solution's piece, where the proximal
       iterations finish in a few steps), smoothing Newton from the warm start, then the proximal iterations if needed */
    if (outer == 1 && smoothing && res > 1e-3 * before && res > s->tol && *steps < limit) {
      PetscReal scale, plain_res = res, start_res = before; /* before: the natural residual at the warm start, nt->rc */
      PetscCall(ImpulseScale(s, nt, n, nc, vd, &scale));
      if (scale > 0) {
        PetscCall(VecCopy(r, nt->rplain));
        PetscCall(MoveTo(nt, nt->rc, r, u, vd));
        res = start_res;
        PetscCall(SolveSmoothed(s, nt, n, nc, nglobal, r, u, vd, wmean, scale, window > 0 ? PetscMin(limit, mark_step + window) : limit,
                                steps, &res));
        /* the proximal iterations go on from the best of the warm start, the plain attempt's end and the smoothing's */
        if (PetscMin(start_res, plain_res) < res) {
          PetscCall(MoveTo(nt, start_res <= plain_res ? nt->rc : nt->rplain, r, u, vd));
          res = PetscMin(start_res, plain_res);
        }
        alpha = nt->alpha; /* the plain attempt's outcome says nothing about the proximal problems from here */
      }
    }
    if (res <= 0.1 * mark_res) { /* a tenfold gain since the mark */
      mark_res  = res;
      mark_step = *steps;
    } else if (window > 0 && *steps - mark_step >= window) {
      PetscCall(PetscInfo(NULL, "attempt stalled: no tenfold gain in %" PetscInt_FMT " Newton steps (natural residual %g)\n",
                          *steps - mark_step, (double)res));
      break;
    }
  }
  *res_io = res;
  PetscFunctionReturn(0);
}

/* An Attempt from r, and when it stalls (-solver_newton_second_window Newton steps without a tenfold gain of the
   natural residual) a second one from the same point with the rest of -solver_max_it and rho times
   -solver_newton_second_rho; the better end of the two is kept. The Alart-Curnier merit has minima that are not
   solutions, and which ones depends on rho: on the pile of radius ratio 100 of docs/running.md (mass ratio 1e4), six
   steps of 40 to 110 contacts that newton left at natural residuals of 1e-4 to 0.1 after 1,000 Newton steps (one
   still at 8e-5 after 20,000) were each solved in 25 to 113 Newton steps with rho / 10. -solver_max_it caps the
   Newton steps of both. */
static PetscErrorCode SolveFrom(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, PetscInt nglobal, Vec r, Vec u, Vec vd, PetscReal wmean,
                                PetscInt *steps, PetscReal *res)
{
  const PetscBool smoothing = (PetscBool)(nt->smoothing && nt->prox != NEWTON_PROX_NONE); /* it hands over to the proximal iterations */
  const PetscBool second    = (PetscBool)(nt->second_rho > 0 && s->max_it - *steps >= 2);
  const PetscReal start_res = *res;

  PetscFunctionBeginUser;
  if (second) PetscCall(VecCopy(r, nt->rstart));
  PetscCall(Attempt(s, nt, n, nc, nglobal, r, u, vd, wmean, smoothing, s->max_it, second ? nt->second_window : 0, steps, res));
  if (second && *res > s->tol && nglobal > 0 && *steps < s->max_it) {
    const PetscReal first = *res;
    PetscCall(PetscInfo(NULL, "first attempt ended at natural residual %g after %" PetscInt_FMT " Newton steps: a second, rho times %g\n",
                        (double)first, *steps, (double)nt->second_rho));
    nt->second_attempts++;
    PetscCall(VecCopy(r, nt->rbest));
    PetscCall(MoveTo(nt, nt->rstart, r, u, vd));
    *res = start_res;
    SetRho(nt, n, nt->rho_factor * nt->second_rho);
    PetscCall(Attempt(s, nt, n, nc, nglobal, r, u, vd, wmean, smoothing, s->max_it, 0, steps, res));
    SetRho(nt, n, nt->rho_factor);
    if (first < *res) {
      PetscCall(MoveTo(nt, nt->rbest, r, u, vd));
      *res = first;
      PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_FALSE, &nt->merit)); /* the statistic, at rho itself */
    }
  }
  PetscFunctionReturn(0);
}

/* Optional NLGS sweeps first (-solver_newton_max_sweeps), until the natural residual is at most
   -solver_newton_switch_tol, the optional interior-point start (-solver_newton_ip_max_it, newton_ip.c) and De Saxce
   start (-solver_newton_desaxce_max_it, newton_desaxce.c), then
   SolveFrom. With a working set (-solver_newton_working_set, newton_working.c) J is
   set up here, once the contacts that the warm start leaves open are known. */
static PetscErrorCode SolverSolve_Newton(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops,
                                         KergsSolveStats *stats)
{
  Newton        *nt = (Newton *)s->data;
  KergsDofLayout layout;
  PetscInt       n, nglobal, nc, steps = 0;
  PetscReal      res = 0.0, wmean = 1.0;
  PetscLogDouble t0, t1;
  Vec            r, u, vd;

  PetscFunctionBeginUser;
  (void)scene;
  PetscCall(PetscTime(&t0));
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, &u, &vd));
  PetscCall(VecGetSize(r, &nglobal));
  nc             = layout.ncomp;
  nt->linear_its = nt->backtracks = nt->failed_searches = nt->failed_linear = 0;
  nt->sweeps = nt->outer = nt->jacobians = nt->stalls = nt->factorizations = nt->reused = nt->second_attempts = 0;
  nt->linear_seconds = nt->sigma = nt->merit = 0.0;
  nt->smooth_steps                           = 0;
  nt->smooth_raised                          = 0;
  nt->desaxce_qps = nt->desaxce_ip_its = 0;
  nt->desaxce_seconds                  = 0.0;
  nt->ip_its                           = 0;
  nt->ip_answer                        = PETSC_FALSE;
  nt->ip_seconds                       = 0.0;
  nt->subdomains_computed              = 0;
  PetscCall(MeanCompliance(s, nt, n, &wmean));
  PetscCall(Sweeps(s, nt, n, nc, r, u, vd, 0, 0.0, &res));
  if (res > nt->switch_tol && nt->max_sweeps > 0) PetscCall(Sweeps(s, nt, n, nc, r, u, vd, nt->max_sweeps, nt->switch_tol, &res));
  if (res > 0) PetscCall(NewtonInteriorPointStart(s, nt, n, nc, r, u, vd, &res));
  if (res > 0) PetscCall(NewtonDeSaxceStart(s, nt, n, nc, wmean, nt->enorm / res, r, u, vd, &res));
  if (nt->working_set) {
    PetscCall(NewtonWorkingSetBegin(s, nt, n, nc, r, u));
    PetscCall(NewtonSetUpJacobian(s, nt, n, nc));
  }
  PetscCall(SolveFrom(s, nt, n, nc, nglobal, r, u, vd, wmean, &steps, &res));
  if (res > s->tol && nglobal > 0) PetscCall(Polish(s, nt, n, nc, r, u, vd, &res));
  stats->iterations = steps;
  stats->criterion  = res;
  stats->reason     = nglobal == 0 ? KERGS_SOLVER_CONVERGED_NO_CONTACTS : KERGS_SOLVER_DIVERGED_MAX_IT;
  if (res <= s->tol) PetscCall(KergsSolverCriterionMet(s, stats));
  PetscCall(PetscTime(&t1));
  stats->sweep_seconds = t1 - t0;
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverStats_Newton(KergsSolver s, KergsSolveStats *st)
{
  Newton *nt = (Newton *)s->data;

  PetscFunctionBeginUser;
  PetscCall(KergsSolveStatsAdd(st, "linear_iterations", (PetscReal)nt->linear_its));
  PetscCall(KergsSolveStatsAdd(st, "linear_seconds", nt->linear_seconds));
  PetscCall(KergsSolveStatsAdd(st, "backtracks", (PetscReal)nt->backtracks));
  PetscCall(KergsSolveStatsAdd(st, "failed_line_searches", (PetscReal)nt->failed_searches));
  PetscCall(KergsSolveStatsAdd(st, "failed_linear_solves", (PetscReal)nt->failed_linear));
  PetscCall(KergsSolveStatsAdd(st, "newton_merit", nt->merit));
  PetscCall(KergsSolveStatsAdd(st, "sweeps", (PetscReal)nt->sweeps));
  PetscCall(KergsSolveStatsAdd(st, "outer_iterations", (PetscReal)nt->outer));
  PetscCall(KergsSolveStatsAdd(st, "jacobians", (PetscReal)nt->jacobians));
  PetscCall(KergsSolveStatsAdd(st, "factorizations", (PetscReal)nt->factorizations));
  PetscCall(KergsSolveStatsAdd(st, "reused_factorizations", (PetscReal)nt->reused));
  PetscCall(KergsSolveStatsAdd(st, "stalled_inner", (PetscReal)nt->stalls));
  PetscCall(KergsSolveStatsAdd(st, "smoothing_steps", (PetscReal)nt->smooth_steps));
  PetscCall(KergsSolveStatsAdd(st, "smoothing_raises", (PetscReal)nt->smooth_raised));
  PetscCall(KergsSolveStatsAdd(st, "second_attempts", (PetscReal)nt->second_attempts));
  if (nt->ip_max_it > 0) {
    PetscCall(KergsSolveStatsAdd(st, "ip_iterations", (PetscReal)nt->ip_its));
    PetscCall(KergsSolveStatsAdd(st, "ip_seconds", nt->ip_seconds));
  }
  if (nt->desaxce_max_it > 0) {
    PetscCall(KergsSolveStatsAdd(st, "desaxce_qps", (PetscReal)nt->desaxce_qps));
    PetscCall(KergsSolveStatsAdd(st, "desaxce_ip_iterations", (PetscReal)nt->desaxce_ip_its));
    PetscCall(KergsSolveStatsAdd(st, "desaxce_seconds", nt->desaxce_seconds));
  }
  if (nt->working_set) {
    PetscCall(KergsSolveStatsAdd(st, "working_set_rebuilds", (PetscReal)nt->rebuilds));
    PetscCall(KergsSolveStatsAdd(st, "deferred_contacts", (PetscReal)nt->left_out));
  }
  PetscFunctionReturn(0);
}

/* A KSP whose options select PCREDUNDANT: the options of its inner KSP (prefix ..._redundant_), which PETSc creates
   and reads only at the first set-up, read now, for -help and the unused-option check. */
static PetscErrorCode ReadRedundantOptions(KSP ksp)
{
  PC        pc;
  KSP       inner;
  PetscBool redundant;

  PetscFunctionBeginUser;
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCREDUNDANT, &redundant));
  if (!redundant) PetscFunctionReturn(0);
  PetscCall(PCRedundantGetKSP(pc, &inner));
  PetscCall(KSPSetFromOptions(inner));
  PetscFunctionReturn(0);
}

/* CHOLMOD's options (-solver_mat_cholmod_*) for newton's Cholesky on one rank: PETSc 3.18 reads them at the first
   symbolic factorization, inside the time loop. That of a 1 x 1 matrix whose factors carry the KSP's prefix reads them
   now, so that -help lists them and a wrong value is refused before any work. Its assembly lists PETSc's options of an
   unprefixed SeqSBAIJ matrix under -help too (-mat_no_inode, -mat_view). */
static PetscErrorCode ReadCholmodOptions(KSP ksp)
{
  PetscBool     help, available;
  PetscMPIInt   rank, size;
  const char   *prefix;
  Mat           A, F;
  MatFactorInfo info;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsHasHelp(NULL, &help));
  PetscCallMPI(MPI_Comm_rank(PetscObjectComm((PetscObject)ksp), &rank));
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)ksp), &size));
  if (rank || (size > 1 && !help)) PetscFunctionReturn(0);
  PetscCall(KSPGetOptionsPrefix(ksp, &prefix));
  PetscCall(MatCreateSeqSBAIJ(PETSC_COMM_SELF, 1, 1, 1, 1, NULL, &A));
  PetscCall(MatGetFactorAvailable(A, MATSOLVERCHOLMOD, MAT_FACTOR_CHOLESKY, &available));
  if (available) {
    PetscCall(MatSetOptionsPrefixFactor(A, prefix)); /* as PCFactor names the factors of J */
    PetscCall(MatSetValue(A, 0, 0, 1.0, INSERT_VALUES));
    PetscCall(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY));
    PetscCall(MatGetFactor(A, MATSOLVERCHOLMOD, MAT_FACTOR_CHOLESKY, &F));
    PetscCall(MatFactorInfoInitialize(&info));
    PetscCall(MatCholeskyFactorSymbolic(F, A, NULL, &info));
    PetscCall(MatDestroy(&F));
  }
  PetscCall(MatDestroy(&A));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverSetFromOptions_Newton(PetscOptionItems *PetscOptionsObject, KergsSolver s)
{
  Newton   *nt          = (Newton *)s->data;
  PetscBool working_set = PETSC_TRUE, working_set_given = PETSC_FALSE; /* on by default (docs/solver.md) */

  PetscFunctionBeginUser;
  PetscOptionsHeadBegin(PetscOptionsObject, "Semismooth Newton on the Alart-Curnier formulation (newton)");
  PetscCall(PetscOptionsReal("-solver_newton_rho", "Augmentation parameter rho = factor / W_aa,nn of each contact", "", nt->rho_factor,
                             &nt->rho_factor, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_shift",
                             "Shift eps of the Jacobian, J + eps I (J has entries of order 1): makes the Newton step defined where stick "
                             "contacts carry a hyperstatic network",
                             "", nt->shift, &nt->shift, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_armijo", "Sufficient decrease of the merit 1/2 |F|^2 in the line search", "", nt->armijo,
                             &nt->armijo, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_newton_max_backtracks",
                            "Halvings of a Newton step before the smallest one is taken anyway", "", nt->max_backtracks,
                            &nt->max_backtracks, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-solver_newton_project", "Line search along the path projected on the Coulomb cones", "",
                             nt->project, &nt->project, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_switch_tol", "NLGS sweeps first, until the natural residual is at most this, then Newton", "",
                             nt->switch_tol, &nt->switch_tol, NULL));
  PetscCall(
      PetscOptionsEnum("-solver_prox",
                       "Proximal term of the outer iterations: identity (W + sigma I), kernel (W + sigma P, P the projector on ker W), "
                       "none (plain Newton)",
                       "", NewtonProxes, (PetscEnum)nt->prox, (PetscEnum *)&nt->prox, NULL));
  PetscCall(PetscOptionsReal("-solver_prox_alpha", "sigma of the proximal term W + sigma I (or P): alpha * natural residual * mean W_nn",
                             "", nt->alpha, &nt->alpha, NULL));
  PetscCall(PetscOptionsReal("-solver_prox_sigma_min", "Smallest sigma / mean W_nn", "", nt->sigma_min, &nt->sigma_min, NULL));
  PetscCall(PetscOptionsReal("-solver_prox_sigma_max", "Largest sigma / mean W_nn", "", nt->sigma_max, &nt->sigma_max, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_prox_inner_max", "Newton steps per outer iteration", "", nt->inner_max,
                            &nt->inner_max, NULL));
  PetscCall(
      KergsOptionsInt(PetscOptionsObject, "-solver_newton_redundant_max",
                      "Several ranks: J gathered whole on every rank and factored there up to this many rows, else GMRES with additive "
                      "Schwarz (overlap 1)",
                      "", nt->redundant_max, &nt->redundant_max, NULL));
  PetscCall(PetscOptionsHasName(NULL, PetscOptionsObject->prefix, "-solver_pc_type", &nt->user_pc));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_newton_reuse_its",
                            "GMRES iterations (relative tolerance 1e-8) preconditioned by the last factorization of J before J is factored "
                            "again, tried when at most half as many contacts changed piece (with additive Schwarz on several ranks: its "
                            "set-up kept under the same rule) (0: factor every changed J)",
                            "", nt->reuse_its, &nt->reuse_its, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_newton_stall_steps",
                            "Newton steps in a row that each cut |F| by less than a tenth and end an outer iteration's Newton (0: never)",
                            "", nt->stall_steps, &nt->stall_steps, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-solver_newton_smoothing",
                             "Smoothing Newton steps first, then the proximal iterations if still needed", "", nt->smoothing,
                             &nt->smoothing, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_smoothing_kappa", "Smoothing Newton: sigma of its Jacobian / (natural residual * mean W_nn)",
                             "", nt->smooth_kappa, &nt->smooth_kappa, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_smoothing_eps", "Smoothing Newton: first eps / largest |rho v^d_n|", "", nt->smooth_eps,
                             &nt->smooth_eps, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_newton_smoothing_raises",
                            "Smoothing Newton: stalls of a solve that raise eps a hundredfold instead of ending the phase (none "
                            "after an interior-point start, unless given)",
                            "", nt->smooth_raises, &nt->smooth_raises, &nt->smooth_raises_set));
  PetscCall(PetscOptionsReal("-solver_newton_second_rho",
                             "A solve that stalls (-solver_newton_second_window) starts again from its start (after any NLGS "
                             "sweeps) with rho times this, and keeps the better end (0: no second attempt)",
                             "", nt->second_rho, &nt->second_rho, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_newton_second_window",
                            "Newton steps without a tenfold gain of the natural residual after which the second attempt starts", "",
                            nt->second_window, &nt->second_window, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_newton_max_sweeps",
                            "NLGS sweeps before Newton, at most (0: none), until -solver_newton_switch_tol", "", nt->max_sweeps,
                            &nt->max_sweeps, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-solver_newton_subdomains_from_w",
                             "Several ranks, additive Schwarz: each subdomain's J computed from W's subdomain, extracted once per J, "
                             "instead of extracted from J at every set-up",
                             "", nt->subdomains_from_w, &nt->subdomains_from_w, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_newton_ip_max_it",
                            "Interior-point iterations on the Stewart-Trinkle LCP (without friction, the normal impulses' LCP) "
                            "before Newton, at most (0: none), until -solver_newton_ip_tol",
                            "", nt->ip_max_it, &nt->ip_max_it, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_ip_tol",
                             "Natural residual that ends the interior-point iterations before Newton (or -solver_tol if looser; "
                             "without friction -solver_tol unless given)",
                             "", nt->ip_tol, &nt->ip_tol, &nt->ip_tol_set));
  PetscCall(
      KergsOptionsInt(PetscOptionsObject, "-solver_newton_desaxce_max_it",
                      "De Saxce QPs (convex, by TAO's interior point) before Newton, at most (0: none), until -solver_newton_desaxce_tol",
                      "", nt->desaxce_max_it, &nt->desaxce_max_it, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_desaxce_tol", "Natural residual that ends the De Saxce QPs before Newton", "", nt->desaxce_tol,
                             &nt->desaxce_tol, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_desaxce_qp_tol",
                             "Each De Saxce QP's natural residual |min(z, grad / W_nn)| that ends it, relative to the impulse scale", "",
                             nt->desaxce_qp_tol, &nt->desaxce_qp_tol, NULL));
  PetscCall(
      KergsOptionsBool(PetscOptionsObject, "-solver_newton_working_set",
                       "Leave the contacts that the warm start leaves open out of J while they stay open (not with -solver_prox kernel)",
                       "", working_set, &working_set, &working_set_given));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-solver_newton_cholesky",
                             "Without friction, on one rank with the default linear solver (not with -solver_prox kernel, nor "
                             "-solver_newton_shift 0): J's rows divided by B make it symmetric positive definite, factored by CHOLMOD's "
                             "Cholesky instead of LU",
                             "", nt->cholesky, &nt->cholesky, NULL));
  PetscOptionsHeadEnd();
  nt->working_set = (PetscBool)(working_set && (working_set_given || nt->prox != NEWTON_PROX_KERNEL)); /* the default gives way */
  PetscCheck(nt->alpha > 0 && PetscIsNormalReal(nt->alpha), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_prox_alpha %g must be positive",
             (double)nt->alpha);
  PetscCheck(nt->sigma_min > 0 && nt->sigma_min <= nt->sigma_max && PetscIsNormalReal(nt->sigma_max), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_prox_sigma_min %g and -solver_prox_sigma_max %g must satisfy 0 < min <= max", (double)nt->sigma_min,
             (double)nt->sigma_max);
  PetscCheck(nt->inner_max >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_prox_inner_max %" PetscInt_FMT " must be at least 1",
             nt->inner_max);
  PetscCheck(nt->redundant_max >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_redundant_max %" PetscInt_FMT " must be non-negative", nt->redundant_max);
  PetscCheck(nt->reuse_its >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_reuse_its %" PetscInt_FMT " must be non-negative",
             nt->reuse_its);
  PetscCheck(nt->stall_steps >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_stall_steps %" PetscInt_FMT " must be non-negative",
             nt->stall_steps);
  PetscCheck(nt->smooth_raises >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_smoothing_raises %" PetscInt_FMT " must be non-negative", nt->smooth_raises);
  PetscCheck(nt->max_sweeps >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_max_sweeps %" PetscInt_FMT " must be non-negative",
             nt->max_sweeps);
  PetscCheck(nt->smooth_kappa >= 0 && !PetscIsInfOrNanReal(nt->smooth_kappa), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_smoothing_kappa %g must be non-negative", (double)nt->smooth_kappa);
  PetscCheck(nt->smooth_eps > 0 && PetscIsNormalReal(nt->smooth_eps), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_smoothing_eps %g must be positive", (double)nt->smooth_eps);
  PetscCheck(nt->rho_factor > 0 && PetscIsNormalReal(nt->rho_factor), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_rho %g must be positive", (double)nt->rho_factor);
  PetscCheck(nt->second_window > 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_second_window %" PetscInt_FMT " must be positive",
             nt->second_window);
  PetscCheck(nt->second_rho == 0 || (nt->second_rho > 0 && PetscIsNormalReal(nt->second_rho * nt->rho_factor)), s->comm,
             PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_second_rho %g must be 0 (none) or positive, with a normal product by -solver_newton_rho %g",
             (double)nt->second_rho, (double)nt->rho_factor);
  PetscCheck(nt->shift >= 0 && !PetscIsInfOrNanReal(nt->shift), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_shift %g must be non-negative", (double)nt->shift);
  PetscCheck(nt->armijo > 0 && nt->armijo < 0.5, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_armijo %g must lie in (0, 0.5)",
             (double)nt->armijo);
  PetscCheck(nt->ip_max_it >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_ip_max_it %" PetscInt_FMT " must be non-negative",
             nt->ip_max_it);
  PetscCheck(nt->ip_tol > 0 && PetscIsNormalReal(nt->ip_tol), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_ip_tol %g must be positive", (double)nt->ip_tol);
  PetscCheck(nt->desaxce_max_it >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_desaxce_max_it %" PetscInt_FMT " must be non-negative", nt->desaxce_max_it);
  PetscCheck(nt->desaxce_tol > 0 && PetscIsNormalReal(nt->desaxce_tol), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_desaxce_tol %g must be positive", (double)nt->desaxce_tol);
  PetscCheck(nt->desaxce_qp_tol > 0 && PetscIsNormalReal(nt->desaxce_qp_tol), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_desaxce_qp_tol %g must be positive", (double)nt->desaxce_qp_tol);
  if (nt->ip_max_it > 0) { /* the interior-point start's KSP options read once here, for -help and the unused-option check */
    KSP ksp;
    PetscCall(NewtonInteriorPointCreateKSP(s, KERGS_DIM, &ksp));
    PetscCall(KSPSetFromOptions(ksp));
    PetscCall(ReadRedundantOptions(ksp));
    PetscCall(KSPDestroy(&ksp));
  }
  if (nt->desaxce_max_it > 0) { /* the QPs' Tao options read once here, for -help and the unused-option check */
    Tao tao;
    PetscCall(NewtonDeSaxceCreateTao(s, &tao));
    PetscCall(TaoDestroy(&tao));
  }
  PetscCheck(nt->max_backtracks >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_max_backtracks %" PetscInt_FMT " must be non-negative", nt->max_backtracks);
  PetscCheck(!(nt->working_set && nt->prox == NEWTON_PROX_KERNEL), s->comm, PETSC_ERR_ARG_INCOMP,
             "-solver_newton_working_set needs -solver_prox identity or none: the kernel term's projector is over every active contact");
  PetscCall(KSPSetFromOptions(nt->ksp));
  if (nt->cholesky) PetscCall(ReadCholmodOptions(nt->ksp));
  s->needs_H = (PetscBool)(nt->prox == NEWTON_PROX_KERNEL); /* the kernel projector factors H_f H_f^T */
  if (nt->prox == NEWTON_PROX_KERNEL && !nt->kernel) {
    PetscCall(KergsKernelCreate(s->comm, &nt->kernel));
    PetscCall(KergsKernelSetOptionsPrefix(nt->kernel, s->prefix));
    PetscCall(KergsKernelSetFromOptions(nt->kernel)); /* -kernel_solver and the like */
    PetscCall(KergsKernelSetActiveOnly(nt->kernel, PETSC_TRUE));
  }
  PetscCall(KSPSetFromOptions(nt->kprox));
  PetscCall(NewtonChoosePresorting(s, nt));
  PetscCall(NewtonChooseSortedSubdomains(nt));
  if (nt->presort) { /* J arrives in W's AMD order (PresortContacts, newton_linear.c) */
    PC        pc;
    PetscBool lu;
    PetscCall(KSPGetPC(nt->ksp, &pc));
    PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCLU, &lu));
    /* LU only: kergs's Cholesky of a frictionless step (the options read again) orders J itself, and
       ChooseFactorization sets this order when it goes back to LU */
    if (lu) PetscCall(PCFactorSetMatOrderingType(pc, MATORDERINGNATURAL));
  }
  PetscCall(KSPSetTolerances(nt->kreuse, 1e-8, PETSC_DEFAULT, PETSC_DEFAULT, nt->reuse_its));
  PetscCall(KSPGMRESSetRestart(nt->kreuse, PetscMax(nt->reuse_its, 1)));
  PetscCall(KSPSetFromOptions(nt->kreuse));
  PetscFunctionReturn(0);
}

/* Without friction: the symmetric form, and the factorization that PETSc's preconditioner last held (its type and
   package, read from the PC: what ran, not what was meant to). */
static PetscErrorCode ViewSymmetricForm(Newton *nt, PetscViewer viewer)
{
  PC            pc;
  PCType        ptype;
  MatSolverType stype = NULL;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(viewer, "Without friction: J's rows divided by B, symmetric, factored by Cholesky\n"));
  if (!nt->symmetric) PetscFunctionReturn(0);
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(PCGetType(pc, &ptype));
  PetscCall(PCFactorGetMatSolverType(pc, &stype));
  PetscCall(PetscViewerASCIIPrintf(viewer, "  in the last step: PC %s, package %s\n", ptype, stype ? stype : "none"));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverView_Newton(KergsSolver s, PetscViewer viewer)
{
  Newton   *nt = (Newton *)s->data;
  PetscBool from_w;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(
      viewer,
      "Semismooth Newton on the Alart-Curnier function (rho = %g / W_nn), Armijo line search (%g, at most %" PetscInt_FMT
      " halvings), shift %g\n",
      (double)nt->rho_factor, (double)nt->armijo, nt->max_backtracks, (double)nt->shift));
  if (nt->smoothing) {
    PetscCall(PetscViewerASCIIPrintf(
        viewer,
        "Smoothing Newton phase first: eps from %g times the largest |rho v^d_n|, Jacobian regularised by %g times the natural residual\n",
        (double)nt->smooth_eps, (double)nt->smooth_kappa));
    if (nt->smooth_raises > 0 && nt->stall_steps > 0)
      PetscCall(PetscViewerASCIIPrintf(
          viewer, "  its first %" PetscInt_FMT " stall(s) of a solve raise eps a hundredfold instead of ending it%s\n", nt->smooth_raises,
          nt->ip_max_it > 0 && !nt->smooth_raises_set ? ", none in a solve that goes on from the interior point's answer" : ""));
  }
  if (nt->second_rho > 0)
    PetscCall(PetscViewerASCIIPrintf(
        viewer, "After %" PetscInt_FMT " Newton steps without a tenfold gain: a second attempt from the same start, rho times %g\n",
        nt->second_window, (double)nt->second_rho));
  if (nt->ip_max_it > 0)
    PetscCall(PetscViewerASCIIPrintf(
        viewer,
        "Interior-point start: at most %" PetscInt_FMT
        " Mehrotra iterations on the Stewart-Trinkle LCP (without friction, the normal impulses' LCP) until the natural residual is %g%s\n",
        nt->ip_max_it, (double)nt->ip_tol, nt->ip_tol_set ? "" : " (without friction: -solver_tol)"));
  if (nt->desaxce_max_it > 0)
    PetscCall(PetscViewerASCIIPrintf(viewer,
                                     "De Saxce start: at most %" PetscInt_FMT
                                     " convex QPs (TAO BQPIP, each to %g of the impulse scale) until "
                                     "the natural residual is %g\n",
                                     nt->desaxce_max_it, (double)nt->desaxce_qp_tol, (double)nt->desaxce_tol));
  if (nt->working_set)
    PetscCall(PetscViewerASCIIPrintf(
        viewer,
        "Working set: contacts the warm start leaves open are left out of J until an iterate takes them off the law's open piece\n"));
  if (nt->presort)
    PetscCall(PetscViewerASCIIPrintf(viewer, "%sJ stored in W's AMD order at every step, and factored in that order\n",
                                     nt->cholesky_ok ? "With friction: " : ""));
  if (nt->cholesky_ok) PetscCall(ViewSymmetricForm(nt, viewer));
  PetscCall(NewtonSubdomainsFromW(nt, &from_w));
  if (from_w)
    PetscCall(PetscViewerASCIIPrintf(viewer,
                                     "Additive Schwarz (several ranks, above %" PetscInt_FMT
                                     " rows of J): each subdomain's J computed from W's subdomain, extracted once per J\n",
                                     nt->redundant_max));
  if (nt->subdomains_computed > 0)
    PetscCall(PetscViewerASCIIPrintf(viewer, "  %" PetscInt_FMT " subdomain matrices built through W's subdomain in the last solve\n",
                                     nt->subdomains_computed));
  if (nt->sorted_subdomains)
    PetscCall(PetscViewerASCIIPrintf(viewer,
                                     "Additive Schwarz (above %" PetscInt_FMT
                                     " rows of J): each subdomain copied into its AMD order and factored in that order\n",
                                     nt->redundant_max));
  PetscCall(KSPView(nt->ksp, viewer));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverDestroy_Newton(KergsSolver s)
{
  Newton *nt = (Newton *)s->data;

  PetscFunctionBeginUser;
  PetscCall(DestroyStepObjects(nt));
  PetscCall(KSPDestroy(&nt->ksp));
  PetscCall(KSPDestroy(&nt->kreuse));
  PetscCall(KSPDestroy(&nt->kprox));
  PetscCall(KergsKernelDestroy(&nt->kernel));
  PetscCall(PetscFree5(nt->A, nt->B, nt->rho, nt->rho_nat, nt->diagblock));
  PetscCall(PetscFree2(nt->Aused, nt->Bused));
  PetscCall(PetscFree2(nt->Afact, nt->Bfact));
  PetscCall(PetscFree(nt->in_J));
  PetscCall(PetscFree(nt));
  s->data = NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverCreate_Newton(KergsSolver s)
{
  Newton *nt;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&nt));
  s->needs_both_triangles = PETSC_TRUE; /* KergsOperatorsGetFullW */
  nt->rho_factor          = 1.0;
  nt->shift               = 1e-8;
  nt->armijo              = 1e-4;
  nt->max_backtracks      = 33;
  nt->switch_tol          = 1e-2;
  nt->max_sweeps          = 0;
  nt->sweep_check         = 10;
  nt->prox                = NEWTON_PROX_IDENTITY;
  nt->alpha               = 10.0;
  nt->alpha_min           = 1e-3;
  nt->sigma_min           = 1e-8;
  nt->sigma_max           = 1.0;
  nt->inner_max           = 20;
  nt->stall_steps         = 5;
  nt->redundant_max       = 15000;
  nt->inner_rtol          = 0.1;
  nt->reuse_its           = 10;
  nt->smooth_kappa        = 0.3;
  nt->smoothing           = PETSC_TRUE;
  nt->subdomains_from_w   = PETSC_TRUE;
  nt->cholesky            = PETSC_TRUE;
  nt->smooth_eps          = 4.0;
  nt->smooth_raises       = 1;
  nt->second_rho          = 0.1;
  nt->second_window       = 250;
  nt->desaxce_tol         = 1e-5;
  nt->ip_tol              = 1e-5;
  nt->desaxce_qp_tol      = 1e-3;
  PetscCall(NewtonCreateLinearSolver(s, nt));
  s->data               = nt;
  s->max_it             = 1000; /* the cap of the tradeoff study's reference runs (docs/tradeoff.md) */
  s->tol                = 1e-8; /* the cheapest tolerance that converges on every step of confine500 (docs/tradeoff.md) */
  s->criterion          = KERGS_CRITERION_NATURAL;
  s->fixed_criterion    = PETSC_TRUE;
  s->iteration_name     = "Newton steps";
  s->ops.setfromoptions = SolverSetFromOptions_Newton;
  s->ops.setup          = SolverSetUp_Newton;
  s->ops.solve          = SolverSolve_Newton;
  s->ops.stats          = SolverStats_Newton;
  s->ops.view           = SolverView_Newton;
  s->ops.destroy        = SolverDestroy_Newton;
  PetscFunctionReturn(0);
}
