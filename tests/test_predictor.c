/* Predictors of NLKerGS-P (src/solver/predictor.c, src/solver/predictors/): known answers on configurations built by the
   engine (scene -> steps -> detect -> operators), the defining equations of Algorithms 4 and 5, the extremes of
   eta and epsilon, the unilateral complementarity, and the same predictions on 1 and 2 ranks.
   Runs on 1 and 2 ranks; every check is global. */
static const char help[] = "kergs predictor tests: column, single disk closed forms, inactive contacts, 1 vs 2 ranks, options.\n";

#include "testing.h"
#include "internals.h"

/* Run nsteps steps, then build the next step's problem: detect, assemble, and mark the active contacts
   (g^- <= 0, the paper's gap rule). */
static PetscErrorCode Prepare(KergsStepper st, PetscInt nsteps, PetscBool **active)
{
  PetscFunctionBeginUser;
  for (PetscInt s = 0; s < nsteps; s++) PetscCall(KergsStepperStep(st));
  PetscCall(KergsContactsDetect(st->contacts, st->scene));
  PetscCall(KergsOperatorsAssemble(st->ops, st->scene, st->contacts));
  PetscCall(PetscMalloc1(st->contacts->n + 1, active));
  /* touching counts to rounding: a settled column's contacts sit at gaps of +-6e-17, whose signs depend on the solver's
     rounding (newton's working set leaves the top one at +5.6e-17, closing at gap / dt within the next step) */
  for (PetscInt k = 0; k < st->contacts->n; k++) (*active)[k] = (PetscBool)(st->contacts->c[k].gap <= 1e-12);
  PetscFunctionReturn(0);
}

/* A predictor configured by opts (after clearing every -predictor_ option), and its r~ for the prepared problem. */
static PetscErrorCode RunPredictor(KergsStepper st, const PetscBool *active, const char *opts, KergsPredictor *p, Vec *r)
{
  const char *names[] = {"-predictor_type",           "-predictor_eta",
                         "-predictor_epsilon",        "-predictor_relative",
                         "-predictor_unilateral_tol", "-predictor_unilateral_max_it"};

  PetscFunctionBeginUser;
  for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++) PetscCall(PetscOptionsClearValue(NULL, names[i]));
  PetscCall(PetscOptionsInsertString(NULL, opts));
  PetscCall(KergsPredictorCreate(st->comm, p));
  PetscCall(KergsPredictorSetFromOptions(*p));
  PetscCall(MatCreateVecs(st->ops->HfT, NULL, r));
  PetscCall(VecSet(*r, 12345.0)); /* the predictor must overwrite every entry */
  PetscCall(KergsPredictorPredict(*p, st->scene, st->contacts, st->ops, active, *r));
  PetscFunctionReturn(0);
}

/* Facts every prediction must satisfy: finite, tangential components zero, inactive contacts zero. */
static PetscErrorCode CheckStructure(KergsStepper st, const PetscBool *active, Vec r, const char *label)
{
  const PetscScalar *ra;
  PetscReal          worst[3] = {0, 0, 0}; /* non-finite count, |tangential|, |inactive| */
  const PetscInt     nc       = st->ops->ncomp;
  char               what[128];

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(r, &ra));
  for (PetscInt k = 0; k < st->contacts->n; k++)
    for (PetscInt c = 0; c < nc; c++) {
      PetscReal v = PetscRealPart(ra[k * nc + c]);
      if (PetscIsInfOrNanReal(v))
        worst[0] += 1;
      else if (c > 0)
        worst[1] = PetscMax(worst[1], PetscAbsReal(v));
      else if (!active[k])
        worst[2] = PetscMax(worst[2], PetscAbsReal(v));
    }
  PetscCall(VecRestoreArrayRead(r, &ra));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, worst, 3, MPIU_REAL, MPIU_MAX, st->comm));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: r~ finite (non-finite entries)", label));
  PetscCall(Check((PetscBool)(worst[0] == 0), what, worst[0], 0));
  if (nc > 1) {
    PetscCall(PetscSNPrintf(what, sizeof(what), "%s: tangential components zero", label));
    PetscCall(Check((PetscBool)(worst[1] == 0), what, worst[1], 0));
  }
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: inactive contacts zero", label));
  PetscCall(Check((PetscBool)(worst[2] == 0), what, worst[2], 0));
  PetscFunctionReturn(0);
}

/* The defining equations of Algorithms 4 and 5, checked from r~ and V~ independently of the predictor's code:
     momentum  M (V~ - V_f^-) = R^d + H_f r~
     law       r~_n = -(dt/eta) v~_n                                              (linear)
               r~_n = -(dt/eps) (g^- + dt ((1 - theta) v^-_n + theta v~_n))       (elastic; theta = 1: Algorithm 5)
   with v~ = H_f^T V~ + H_g^T V_g^+ and v^- = H_f^T V_f^- + H_g^T V_g^+, on the active contacts. Together they
   are K V~ = b. Each residual is relative to the size of the terms it sums (a backward error, like that of
   K V~ = b relative to |K| |V~| + |b|), so that it stays meaningful at the extremes of eta and epsilon, where
   the terms nearly cancel. */
static PetscErrorCode DefiningResiduals(KergsStepper st, KergsPredictor p, const PetscBool *active, Vec r, PetscBool elastic,
                                        PetscReal *mom, PetscReal *law)
{
  KergsOperators     ops = st->ops;
  Vec                a, b, vt, vg, vminus;
  const PetscScalar *ra, *va, *vm;
  PetscReal          dt = st->scene->dt, th = st->scene->theta, res[2] = {0, 0}, n[4], normH, nV, ngv = 0, mscale, terms, coef;
  const PetscInt     nc = ops->ncomp;

  PetscFunctionBeginUser;
  if (!p->Vtilde) { /* a predictor that solves a DOF-space system keeps V~: without it, nothing to check */
    PetscCall(Checkf(PETSC_FALSE, 0, 1, "predictor %s kept its V~", p->type));
    *mom = *law = PETSC_MAX_REAL;
    PetscFunctionReturn(0);
  }
  /* momentum */
  PetscCall(VecDuplicate(ops->Vf, &a));
  PetscCall(VecDuplicate(ops->Vf, &b));
  PetscCall(VecPointwiseDivide(a, p->Vtilde, ops->Minv)); /* M V~ */
  PetscCall(VecNorm(a, NORM_INFINITY, &n[0]));
  PetscCall(VecPointwiseDivide(b, ops->Vf, ops->Minv)); /* M V^- */
  PetscCall(VecNorm(b, NORM_INFINITY, &n[1]));
  PetscCall(VecAXPY(a, -1.0, b));
  PetscCall(VecAXPY(a, -1.0, ops->Rd));
  PetscCall(VecNorm(ops->Rd, NORM_INFINITY, &n[2]));
  PetscCall(MatMultTranspose(ops->HfT, r, b)); /* H_f r~ */
  PetscCall(VecNorm(b, NORM_INFINITY, &n[3]));
  PetscCall(VecAXPY(a, -1.0, b));
  PetscCall(VecNorm(a, NORM_INFINITY, &res[0]));
  mscale = n[0] + n[1] + n[2] + n[3];
  /* law */
  PetscCall(MatCreateVecs(ops->HfT, NULL, &vt));
  PetscCall(VecDuplicate(vt, &vg));
  PetscCall(MatMult(ops->HfT, p->Vtilde, vt));
  if (ops->HgT)
    PetscCall(MatMult(ops->HgT, ops->Vg, vg));
  else
    PetscCall(VecZeroEntries(vg));
  PetscCall(VecNorm(vg, NORM_INFINITY, &ngv));
  PetscCall(VecAXPY(vt, 1.0, vg));
  PetscCall(VecDuplicate(vg, &vminus));
  PetscCall(MatMultAdd(ops->HfT, ops->Vf, vg, vminus)); /* v^- = H_f^T V_f^- + H_g^T V_g^+ */
  PetscCall(MatNorm(ops->HfT, NORM_INFINITY, &normH));
  PetscCall(VecNorm(p->Vtilde, NORM_INFINITY, &nV));
  PetscCall(VecNorm(r, NORM_INFINITY, &n[0]));
  PetscCall(VecNorm(vminus, NORM_INFINITY, &n[1]));
  n[2] = 0; /* largest |g^-| over active contacts */
  PetscCall(VecGetArrayRead(r, &ra));
  PetscCall(VecGetArrayRead(vt, &va));
  PetscCall(VecGetArrayRead(vminus, &vm));
  for (PetscInt k = 0; k < st->contacts->n; k++) {
    PetscReal g = st->contacts->c[k].gap, rk = PetscRealPart(ra[k * nc]), v = PetscRealPart(va[k * nc]), vmk = PetscRealPart(vm[k * nc]), e;
    if (!active[k]) continue;
    n[2] = PetscMax(n[2], PetscAbsReal(g));
    if (elastic)
      e = rk + dt / p->epsilon_abs * (g + dt * ((1 - th) * vmk + th * v));
    else
      e = rk + dt / p->eta_abs * v;
    res[1] = PetscMax(res[1], PetscAbsReal(e));
  }
  PetscCall(VecRestoreArrayRead(vminus, &vm));
  PetscCall(VecRestoreArrayRead(vt, &va));
  PetscCall(VecRestoreArrayRead(r, &ra));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &res[1], 1, MPIU_REAL, MPIU_MAX, st->comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &n[2], 1, MPIU_REAL, MPIU_MAX, st->comm));
  /* size of the terms of the law: r~ and (dt/eps) g^+ or (dt/eta) v~ */
  coef  = elastic ? dt / p->epsilon_abs : dt / p->eta_abs;
  terms = elastic ? coef * (n[2] + dt * (n[1] + normH * nV + ngv)) : coef * (normH * nV + ngv);
  *law  = res[1] / PetscMax(n[0] + terms, PETSC_SMALL);
  /* the momentum residual is that of K V~ = b once the law is substituted: its terms include H_f D (dt/eps) g^+ */
  *mom = res[0] / PetscMax(mscale + normH * terms, PETSC_SMALL);
  PetscCall(VecDestroy(&a));
  PetscCall(VecDestroy(&b));
  PetscCall(VecDestroy(&vt));
  PetscCall(VecDestroy(&vg));
  PetscCall(VecDestroy(&vminus));
  PetscFunctionReturn(0);
}

/* Largest normal impulse and, for the unilateral predictor, the complementarity of v = W r~ + v^d on the
   active normal components: max |min(r_n, v_n / W_nn)| relative to max r_n, and min r_n. */
static PetscErrorCode Complementarity(KergsStepper st, const PetscBool *active, Vec r, PetscReal *res, PetscReal *rmin)
{
  KergsOperators     ops = st->ops;
  Vec                v, d;
  const PetscScalar *ra, *va, *da;
  PetscReal          loc[3] = {0, 0, 0}; /* max |min(r, v/w)|, max r, max(-r) */
  const PetscInt     nc     = ops->ncomp;

  PetscFunctionBeginUser;
  PetscCall(MatCreateVecs(ops->W, &d, &v));
  PetscCall(MatMultAdd(ops->W, r, ops->vd, v));
  PetscCall(MatGetDiagonal(ops->W, d));
  PetscCall(VecGetArrayRead(r, &ra));
  PetscCall(VecGetArrayRead(v, &va));
  PetscCall(VecGetArrayRead(d, &da));
  for (PetscInt k = 0; k < st->contacts->n; k++) {
    PetscReal rk = PetscRealPart(ra[k * nc]), vk = PetscRealPart(va[k * nc]) / PetscRealPart(da[k * nc]);
    if (!active[k]) continue;
    loc[0] = PetscMax(loc[0], PetscAbsReal(PetscMin(rk, vk)));
    loc[1] = PetscMax(loc[1], rk);
    loc[2] = PetscMax(loc[2], -rk);
  }
  PetscCall(VecRestoreArrayRead(d, &da));
  PetscCall(VecRestoreArrayRead(v, &va));
  PetscCall(VecRestoreArrayRead(r, &ra));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, loc, 3, MPIU_REAL, MPIU_MAX, st->comm));
  *res  = loc[0] / PetscMax(loc[1], PETSC_SMALL);
  *rmin = -loc[2];
  PetscCall(VecDestroy(&v));
  PetscCall(VecDestroy(&d));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------- */
/* A column of N disks on a floor: the contact below disk k carries (N - k) m g dt.                       */

/* Largest error of the normal impulses against the static column, relative to the floor's N m g dt. */
static PetscErrorCode ColumnError(KergsStepper st, Vec r, PetscInt N, PetscReal *err)
{
  const PetscScalar *ra;
  PetscReal          w, *mass;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(st->scene->ndisks, &mass));
  PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->mass, 1, mass));
  w = mass[0] * 10.0 * st->scene->dt;
  PetscCall(PetscFree(mass));
  *err = 0;
  PetscCall(VecGetArrayRead(r, &ra));
  for (PetscInt k = 0; k < st->contacts->n; k++) {
    const KergsContact *c    = &st->contacts->c[k];
    PetscReal           want = (c->kind == KERGS_CONTACT_DISK_WALL ? N : N - 1 - st->scene->gidx[c->a]) * w;
    *err                     = PetscMax(*err, PetscAbsReal(PetscRealPart(ra[k * st->ops->ncomp]) - want) / (N * w));
  }
  PetscCall(VecRestoreArrayRead(r, &ra));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, err, 1, MPIU_REAL, MPIU_MAX, st->comm));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestColumn(PetscReal mu)
{
  const PetscInt  N       = 6;
  const PetscReal etas[3] = {1e-4, 1e-8, 1e-12};
  KergsStepper    st;
  KergsPredictor  p;
  PetscBool      *active;
  Vec             r;
  PetscReal       err, errs[3], mom, law, norm, cres, rmin;
  char            opts[1024], what[128], lab[32];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(lab, sizeof(lab), "column mu=%g", (double)mu));
  PetscCall(PetscSNPrintf(
      opts, sizeof(opts),
      "-gravity 0,-10 -friction %g -dt 1e-3 -disks_source lattice -lattice_type square -lattice_n 1,%" PetscInt_FMT " -lattice_radius 0.1 "
      "-lattice_origin 0,0.1 -walls floor -wall_floor_a -1,0 -wall_floor_b 1,0 -wall_floor_infinite -alert 0.01 -solver_tol 1e-13 "
      "-solver_max_it 20000",
      (double)mu, N));
  PetscCall(MakeStepperOn(PETSC_COMM_WORLD, opts, &st));
  /* lattice gaps of +1e-17 keep contacts inactive until each disk has fallen for a step: N + 4 steps settle it */
  PetscCall(Prepare(st, N + 4, &active));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: %" PetscInt_FMT " contacts, components per contact", lab, N));
  PetscCall(Check((PetscBool)(st->contacts->nglobal == N && st->ops->ncomp == (mu > 0 ? 2 : 1)), what, (PetscReal)st->ops->ncomp,
                  mu > 0 ? 2 : 1));

  PetscCall(RunPredictor(st, active, "-predictor_type none", &p, &r));
  PetscCall(VecNorm(r, NORM_INFINITY, &norm));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s, none: r~ = 0", lab));
  PetscCall(Check((PetscBool)(norm == 0), what, norm, 0));
  PetscCall(KergsPredictorDestroy(&p));
  PetscCall(VecDestroy(&r));

  /* unilateral: exact for a frictionless column (W_nn is non-singular, the solution unique) */
  PetscCall(RunPredictor(st, active, "-predictor_type unilateral", &p, &r));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s, unilateral: every contact active", lab));
  PetscCall(Check((PetscBool)(p->nactive == N), what, (PetscReal)p->nactive, N));
  PetscCall(CheckStructure(st, active, r, "column, unilateral"));
  PetscCall(ColumnError(st, r, N, &err));
  PetscCall(
      PetscSNPrintf(what, sizeof(what), "%s, unilateral: r_n = (N - k) m g dt (relative error, %" PetscInt_FMT " sweeps)", lab, p->sweeps));
  PetscCall(Check((PetscBool)(err < 1e-8 && p->converged), what, err, 0));
  PetscCall(Complementarity(st, active, r, &cres, &rmin));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s, unilateral: complementarity |min(r, v/W)| / max r", lab));
  PetscCall(Check((PetscBool)(cres < 1e-8 && rmin >= 0), what, cres, 0));
  PetscCall(KergsPredictorDestroy(&p));
  PetscCall(VecDestroy(&r));
  /* the same from a cold start (the warm start above is the engine's converged impulses) */
  for (PetscInt k = 0; k < st->contacts->n; k++) st->contacts->c[k].r[0] = st->contacts->c[k].r[1] = 0;
  PetscCall(RunPredictor(st, active, "-predictor_type unilateral", &p, &r));
  PetscCall(ColumnError(st, r, N, &err));
  PetscCall(
      PetscSNPrintf(what, sizeof(what), "%s, unilateral from r = 0: r_n = (N - k) m g dt (%" PetscInt_FMT " sweeps)", lab, p->sweeps));
  PetscCall(Check((PetscBool)(err < 1e-8 && p->converged && p->sweeps > 1), what, err, 0));
  PetscCall(KergsPredictorDestroy(&p));
  PetscCall(VecDestroy(&r));

  /* linear: tends to the static impulses as eta -> 0, and satisfies its own equations at every eta */
  for (PetscInt i = 0; i < 3; i++) {
    PetscCall(PetscSNPrintf(opts, sizeof(opts), "-predictor_type linear -predictor_eta %g", (double)etas[i]));
    PetscCall(RunPredictor(st, active, opts, &p, &r));
    PetscCall(CheckStructure(st, active, r, "column, linear"));
    PetscCall(ColumnError(st, r, N, &errs[i]));
    PetscCall(DefiningResiduals(st, p, active, r, PETSC_FALSE, &mom, &law));
    PetscCall(PetscSNPrintf(what, sizeof(what), "%s, linear eta=%g: momentum and law residuals (max)", lab, (double)etas[i]));
    PetscCall(Check((PetscBool)(mom < 1e-10 && law < 1e-10 && p->converged), what, PetscMax(mom, law), 0));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "     %s, linear eta=%g: error against the static column %.3e\n", lab, (double)etas[i],
                          (double)errs[i]));
    PetscCall(KergsPredictorDestroy(&p));
    PetscCall(VecDestroy(&r));
  }
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s, linear: error decreases with eta (1e-4 > 1e-8 > 1e-12)", lab));
  PetscCall(Check((PetscBool)(errs[0] > errs[1] && errs[1] > errs[2]), what, errs[2], 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s, linear eta=1e-4: error of the order of eta (between 1e-6 and 1e-2)", lab));
  PetscCall(Check((PetscBool)(errs[0] > 1e-6 && errs[0] < 1e-2), what, errs[0], 1e-4));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s, linear eta=1e-12: static impulses (relative error)", lab));
  PetscCall(Check((PetscBool)(errs[2] < 1e-9), what, errs[2], 0));

  PetscCall(PetscFree(active));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------- */
/* One disk on a floor, interpenetration delta, initial velocity v0 (normal): closed forms for one DOF.     */
/* With m V~ = m v0 + m G dt + r (G = -10) and r = -(dt/eps)(g + dt((1-theta) v0 + theta V~)):            */
/*   elastic  r = -m dt (g + dt v0 + theta G dt^2) / (eps m + theta dt^2)                                */
/*   linear   r = -(dt/eta) V~  =>  r = -m dt (v0 + G dt) / (eta m + dt)                                 */

static PetscErrorCode TestSingleDisk(PetscReal theta, PetscReal v0)
{
  const PetscReal R = 0.1, delta = 1e-4, dt = 1e-3, G = -10;
  const PetscReal eps[5] = {1e-12, 1e-8, 1e-4, 1e-2, 1};
  KergsStepper    st;
  KergsPredictor  p;
  PetscBool      *active;
  Vec             r;
  PetscReal       m, g, rn = 0, want, rel, worst = 0, mom, law, tol;
  char            opts[1024], what[160];

  PetscFunctionBeginUser;
  PetscCall(
      PetscSNPrintf(opts, sizeof(opts),
                    "-gravity 0,%g -dt %g -theta %g -disks_source list -disks_x 0,%.17g -disks_radius %g -disks_velocity 0,%g -walls floor "
                    "-wall_floor_a -1,0 -wall_floor_b 1,0 -wall_floor_infinite -alert 0.01",
                    (double)G, (double)dt, (double)theta, (double)(R - delta), (double)R, (double)v0));
  PetscCall(MakeStepperOn(PETSC_COMM_WORLD, opts, &st));
  PetscCall(Prepare(st, 0, &active));
  PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->mass, 1, &m)); /* the one disk, from its owner */
  g = st->contacts->nglobal == 1 && st->contacts->n == 1 ? st->contacts->c[0].gap : 0;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &g, 1, MPIU_REAL, MPIU_MIN, PETSC_COMM_WORLD));
  PetscCall(PetscSNPrintf(what, sizeof(what), "disk theta=%g v0=%g: one contact with gap -delta", (double)theta, (double)v0));
  PetscCall(Check((PetscBool)(st->contacts->nglobal == 1 && PetscAbsReal(g + delta) < 1e-12), what, g, -delta));

  for (PetscInt i = 0; i < 6; i++) {
    PetscBool absolute = (PetscBool)(i == 5); /* last: the paper's absolute epsilon in s^2/kg */
    if (absolute)
      PetscCall(PetscSNPrintf(opts, sizeof(opts), "-predictor_type elastic -predictor_relative 0 -predictor_epsilon 3e-7"));
    else
      PetscCall(PetscSNPrintf(opts, sizeof(opts), "-predictor_type elastic -predictor_epsilon %g", (double)eps[i]));
    PetscCall(RunPredictor(st, active, opts, &p, &r));
    PetscCall(VecSum(r, &rn)); /* the one normal impulse */
    want = -m * dt * (g + dt * v0 + theta * G * dt * dt) / (p->epsilon_abs * m + theta * dt * dt);
    rel  = PetscAbsReal(rn - want) / PetscAbsReal(want);
    /* rounding: r = -(dt/eps)(g + dt v~) cancels as eps -> 0; Algorithm 5's form loses about 1e-16 / eps_rel */
    tol = 1e-12 + 1e-15 * dt * dt / (p->epsilon_abs * m);
    PetscCall(PetscSNPrintf(what, sizeof(what), "disk theta=%g v0=%g, elastic eps=%g%s: closed form (relative error)", (double)theta,
                            (double)v0, (double)(absolute ? 3e-7 : eps[i]), absolute ? " s^2/kg" : ""));
    PetscCall(Check((PetscBool)(rel < tol && rn > 0 && !PetscIsInfOrNanReal(rn)), what, rn, want));
    PetscCall(DefiningResiduals(st, p, active, r, PETSC_TRUE, &mom, &law));
    worst = PetscMax(worst, PetscMax(mom, law));
    PetscCall(KergsPredictorDestroy(&p));
    PetscCall(VecDestroy(&r));
  }
  PetscCall(PetscSNPrintf(what, sizeof(what), "disk theta=%g v0=%g, elastic: momentum and law residuals (max over eps)", (double)theta,
                          (double)v0));
  PetscCall(Check((PetscBool)(worst < 1e-10), what, worst, 0));

  /* a softer elastic contact closes less of the gap: r decreases with epsilon */
  {
    PetscReal r1, r2;
    PetscCall(RunPredictor(st, active, "-predictor_type elastic -predictor_epsilon 1e-3", &p, &r));
    PetscCall(VecSum(r, &r1));
    PetscCall(KergsPredictorDestroy(&p));
    PetscCall(VecDestroy(&r));
    PetscCall(RunPredictor(st, active, "-predictor_type elastic -predictor_epsilon 1", &p, &r));
    PetscCall(VecSum(r, &r2));
    PetscCall(KergsPredictorDestroy(&p));
    PetscCall(VecDestroy(&r));
    PetscCall(PetscSNPrintf(what, sizeof(what), "disk theta=%g v0=%g, elastic: stiffer pushes harder (r(1e-3) > r(1))", (double)theta,
                            (double)v0));
    PetscCall(Check((PetscBool)(r1 > r2 && r2 > 0), what, r1, r2));
  }

  /* linear, relative and absolute eta */
  for (PetscInt i = 0; i < 3; i++) {
    if (i < 2)
      PetscCall(PetscSNPrintf(opts, sizeof(opts), "-predictor_type linear -predictor_eta %g", i ? 1e-12 : 1e-6));
    else
      PetscCall(PetscSNPrintf(opts, sizeof(opts), "-predictor_type linear -predictor_relative 0 -predictor_eta 1e-5"));
    PetscCall(RunPredictor(st, active, opts, &p, &r));
    PetscCall(VecSum(r, &rn));
    want = -m * dt * (v0 + G * dt) / (p->eta_abs * m + dt);
    rel  = PetscAbsReal(rn - want) / PetscAbsReal(want);
    PetscCall(PetscSNPrintf(what, sizeof(what), "disk theta=%g v0=%g, linear eta=%s: closed form (relative error)", (double)theta,
                            (double)v0, i == 0 ? "1e-6" : (i == 1 ? "1e-12" : "1e-5 s/kg")));
    PetscCall(Check((PetscBool)(rel < 1e-10), what, rn, want));
    PetscCall(KergsPredictorDestroy(&p));
    PetscCall(VecDestroy(&r));
  }
  PetscCall(PetscFree(active));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------- */
/* Two disks stacked on a floor, the upper one not touching (gap within the alert distance): its contact   */
/* is potential but inactive and gets r~ = 0; active = NULL means g^- <= 0.                                 */

static PetscErrorCode TestInactive(void)
{
  const char    *types[] = {"none", "linear", "unilateral", "elastic"};
  KergsStepper   st;
  KergsPredictor p;
  PetscBool     *active;
  Vec            r, r0;
  PetscReal      rfloor, diff, n0;
  char           what[128], opts[128];

  PetscFunctionBeginUser;
  PetscCall(MakeStepperOn(PETSC_COMM_WORLD,
                          "-gravity 0,-10 -dt 1e-3 -friction 0.2 -disks_source list -disks_x 0,0.0999,0,0.3039 -disks_radius 0.1 -walls "
                          "floor -wall_floor_a -1,0 "
                          "-wall_floor_b 1,0 -wall_floor_infinite -alert 0.01",
                          &st));
  PetscCall(Prepare(st, 0, &active));
  PetscCall(Check((PetscBool)(st->contacts->nglobal == 2), "inactive: 2 potential contacts (floor g<0, upper pair g>0)",
                  (PetscReal)st->contacts->nglobal, 2));
  for (PetscInt t = 0; t < 4; t++) {
    PetscCall(PetscSNPrintf(opts, sizeof(opts), "-predictor_type %s", types[t]));
    PetscCall(RunPredictor(st, active, opts, &p, &r));
    PetscCall(PetscSNPrintf(what, sizeof(what), "inactive, %s", types[t]));
    PetscCall(CheckStructure(st, active, r, what));
    PetscCall(PetscSNPrintf(what, sizeof(what), "inactive, %s: one active contact", types[t]));
    PetscCall(Check((PetscBool)(p->nactive == 1), what, (PetscReal)p->nactive, 1));
    PetscCall(VecSum(r, &rfloor));
    PetscCall(PetscSNPrintf(what, sizeof(what), "inactive, %s: the floor contact pushes (r_n > 0) unless none", types[t]));
    PetscCall(Check((PetscBool)(t == 0 ? rfloor == 0 : rfloor > 0), what, rfloor, 0));
    /* active = NULL: the same prediction (gap rule g^- <= 0) */
    PetscCall(VecDuplicate(r, &r0));
    PetscCall(KergsPredictorPredict(p, st->scene, st->contacts, st->ops, NULL, r0));
    PetscCall(VecAXPY(r0, -1.0, r));
    PetscCall(VecNorm(r0, NORM_INFINITY, &diff));
    PetscCall(VecNorm(r, NORM_INFINITY, &n0));
    PetscCall(PetscSNPrintf(what, sizeof(what), "inactive, %s: active = NULL gives the same r~", types[t]));
    PetscCall(Check((PetscBool)(diff <= 1e-14 * n0), what, diff, 0));
    PetscCall(VecDestroy(&r0));
    PetscCall(KergsPredictorDestroy(&p));
    PetscCall(VecDestroy(&r));
  }
  PetscCall(PetscFree(active));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------- */
/* A confined hex lattice (hyperstatic: W singular), frictional, with a driven wall pushing inward (H_g):  */
/* the same problem built on PETSC_COMM_SELF (a sequential reference on every rank) and PETSC_COMM_WORLD.  */

/* 8 x 6 disks of radius 0.05 on a hex lattice whose neighbours are 0.0999 apart (overlap 1e-4), in a box whose
   walls overlap the outer disks by 1e-4; the right wall moves outward at 0.05 (inward, the confined
   lattice would have no solution at velocity level). */
static PetscErrorCode LatticeOptions(char *opts, size_t len)
{
  const PetscInt  nx = 8, ny = 6;
  const PetscReal R = 0.05, s = 2 * R - 1e-4, h = s * PetscSqrtReal(3.0) / 2, x0 = R - 1e-4;
  size_t          n;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(
      opts, len,
      "-gravity 0,-10 -dt 1e-3 -friction 0.3 -disks_source list -disks_radius %g -box 0,0,%.17g,%.17g -wall_box_right_velocity 0.05,0 "
      "-alert 0.005 -disks_x ",
      (double)R, (double)(x0 + (nx - 0.5) * s + x0), (double)(x0 + (ny - 1) * h + x0)));
  for (PetscInt j = 0; j < ny; j++)
    for (PetscInt i = 0; i < nx; i++) {
      PetscCall(PetscStrlen(opts, &n));
      PetscCall(PetscSNPrintf(opts + n, len - n, "%s%.17g,%.17g", i || j ? "," : "", (double)(x0 + i * s + (j % 2) * s / 2),
                              (double)(x0 + j * h)));
    }
  PetscFunctionReturn(0);
}

/* All of a distributed Vec on every rank. */
static PetscErrorCode GatherAll(Vec x, Vec *all)
{
  VecScatter sc;

  PetscFunctionBeginUser;
  PetscCall(VecScatterCreateToAll(x, &sc, all));
  PetscCall(VecScatterBegin(sc, x, *all, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(sc, x, *all, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterDestroy(&sc));
  PetscFunctionReturn(0);
}

/* max |a - b| / max |b| over all entries, a distributed, b sequential (the reference), max over ranks */
static PetscErrorCode CompareWithReference(Vec a, Vec b, PetscReal *rel)
{
  Vec       all;
  PetscReal d, nb;
  PetscInt  na, nbs;

  PetscFunctionBeginUser;
  PetscCall(GatherAll(a, &all));
  PetscCall(VecGetSize(all, &na));
  PetscCall(VecGetSize(b, &nbs));
  if (na != nbs) { /* global sizes: the same answer on every rank */
    PetscCall(Check(PETSC_FALSE, "prediction on all ranks has the size of the 1-rank one", na, nbs));
    PetscCall(VecDestroy(&all));
    *rel = PETSC_MAX_REAL;
    PetscFunctionReturn(0);
  }
  PetscCall(VecNorm(b, NORM_INFINITY, &nb));
  PetscCall(VecAXPY(all, -1.0, b));
  PetscCall(VecNorm(all, NORM_INFINITY, &d));
  *rel = d / PetscMax(nb, PETSC_SMALL);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, rel, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
  PetscCall(VecDestroy(&all));
  PetscFunctionReturn(0);
}

/* Identity of each contact, (a, b, kind) with global disk indices as one real, in the global order of ops->r's
   normal components. */
static PetscErrorCode ContactKeys(KergsStepper st, Vec *keys)
{
  PetscScalar *k;

  PetscFunctionBeginUser;
  PetscCall(VecCreateMPI(st->comm, st->contacts->n, PETSC_DETERMINE, keys));
  PetscCall(VecGetArray(*keys, &k));
  for (PetscInt i = 0; i < st->contacts->n; i++) {
    const KergsContact *c = &st->contacts->c[i];
    const PetscInt      b = c->kind == KERGS_CONTACT_DISK_WALL ? c->b : st->scene->gidx[c->b];
    k[i]                  = 1e6 * st->scene->gidx[c->a] + 1e2 * b + (c->kind == KERGS_CONTACT_DISK_WALL ? 1 : 0);
  }
  PetscCall(VecRestoreArray(*keys, &k));
  PetscFunctionReturn(0);
}

/* |H_f r~|: unique for the frictionless unilateral problem even where r~ is not */
static PetscErrorCode HfNorm(KergsStepper st, Vec r, Vec *Hr)
{
  PetscFunctionBeginUser;
  PetscCall(VecDuplicate(st->ops->Vf, Hr));
  PetscCall(MatMultTranspose(st->ops->HfT, r, *Hr));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestLatticeRanks(void)
{
  const char    *cases[] = {"-predictor_type linear", "-predictor_type elastic", "-predictor_type linear -predictor_eta 1e-12",
                            "-predictor_type elastic -predictor_epsilon 1e-12",
                            "-predictor_type unilateral -predictor_unilateral_tol 1e-13 -predictor_unilateral_max_it 20000"};
  KergsStepper   seq, par;
  PetscBool     *aseq, *apar;
  Vec            rseq, rpar, kseq, kpar, Hseq, Hpar, rall;
  KergsPredictor pseq, ppar;
  PetscReal      rel, mom, law, cres, rmin, na, nk;
  char           what[200], opts[8192];

  PetscFunctionBeginUser;
  PetscCall(LatticeOptions(opts, sizeof(opts)));
  PetscCall(MakeStepperOn(PETSC_COMM_SELF, opts, &seq));
  PetscCall(Prepare(seq, 0, &aseq));
  PetscCall(MakeStepperOn(PETSC_COMM_WORLD, opts, &par));
  PetscCall(Prepare(par, 0, &apar));
  PetscCall(ContactKeys(seq, &kseq));
  PetscCall(ContactKeys(par, &kpar));
  PetscCall(CompareWithReference(kpar, kseq, &rel));
  PetscCall(Check((PetscBool)(rel == 0 && par->contacts->nglobal > 100), "lattice: same contacts in the same order on 1 and all ranks",
                  (PetscReal)par->contacts->nglobal, (PetscReal)seq->contacts->nglobal));
  PetscCall(Check((PetscBool)(par->ops->HgT != NULL && par->ops->ncomp == 2), "lattice: driven wall (H_g) and friction (2 components)",
                  (PetscReal)par->ops->ncomp, 2));

  for (size_t c = 0; c < sizeof(cases) / sizeof(cases[0]); c++) {
    PetscBool unil = (PetscBool)(c == 4), elas = (PetscBool)(c == 1 || c == 3);
    PetscCall(RunPredictor(seq, aseq, cases[c], &pseq, &rseq));
    PetscCall(RunPredictor(par, apar, cases[c], &ppar, &rpar));
    PetscCall(PetscSNPrintf(what, sizeof(what), "lattice, %s", cases[c] + 16));
    PetscCall(CheckStructure(par, apar, rpar, what));
    if (unil) {
      /* r~ is not unique (hyperstatic), H_f r~ is: compare it; complementarity on both */
      PetscCall(HfNorm(seq, rseq, &Hseq));
      PetscCall(HfNorm(par, rpar, &Hpar));
      PetscCall(CompareWithReference(Hpar, Hseq, &rel));
      PetscCall(PetscSNPrintf(what, sizeof(what),
                              "lattice, unilateral: H_f r~ on all ranks = on one (relative, %" PetscInt_FMT " / %" PetscInt_FMT " sweeps)",
                              ppar->sweeps, pseq->sweeps));
      PetscCall(Check((PetscBool)(rel < 1e-8), what, rel, 0));
      PetscCall(Complementarity(par, apar, rpar, &cres, &rmin));
      PetscCall(Check((PetscBool)(cres < 1e-8 && rmin >= 0 && ppar->converged),
                      "lattice, unilateral: complementarity |min(r, v/W)| / max r, r >= 0", cres, 0));
      PetscCall(VecDestroy(&Hseq));
      PetscCall(VecDestroy(&Hpar));
    } else {
      PetscCall(CompareWithReference(rpar, rseq, &rel));
      PetscCall(PetscSNPrintf(what, sizeof(what), "lattice, %s: r~ on all ranks = on one (relative)", cases[c] + 16));
      PetscCall(Check((PetscBool)(rel < 1e-10), what, rel, 0));
      PetscCall(GatherAll(rpar, &rall));
      PetscCall(VecNorm(rall, NORM_2, &na));
      PetscCall(VecNorm(rseq, NORM_2, &nk));
      PetscCall(PetscSNPrintf(what, sizeof(what), "lattice, %s: |r~|_2 on all ranks = on one", cases[c] + 16));
      PetscCall(Check((PetscBool)(PetscAbsReal(na - nk) <= 1e-10 * nk && nk > 0), what, na, nk));
      PetscCall(VecDestroy(&rall));
      PetscCall(DefiningResiduals(par, ppar, apar, rpar, elas, &mom, &law));
      PetscCall(PetscSNPrintf(what, sizeof(what), "lattice, %s: momentum and law residuals", cases[c] + 16));
      PetscCall(Check((PetscBool)(mom < 1e-10 && law < 1e-10), what, PetscMax(mom, law), 0));
    }
    PetscCall(KergsPredictorDestroy(&pseq));
    PetscCall(KergsPredictorDestroy(&ppar));
    PetscCall(VecDestroy(&rseq));
    PetscCall(VecDestroy(&rpar));
  }
  PetscCall(VecDestroy(&kseq));
  PetscCall(VecDestroy(&kpar));
  PetscCall(PetscFree(aseq));
  PetscCall(PetscFree(apar));
  PetscCall(KergsStepperDestroy(&seq));
  PetscCall(KergsStepperDestroy(&par));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------- */
/* Bad options are refused with the option's name.                                                       */

static PetscErrorCode CheckError(const char *opts, PetscErrorCode want)
{
  KergsPredictor p;
  PetscErrorCode ierr;
  char           what[160];

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsClear(NULL));
  PetscCall(PetscOptionsInsertString(NULL, opts));
  PetscCall(KergsPredictorCreate(PETSC_COMM_WORLD, &p));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KergsPredictorSetFromOptions(p);
  PetscCall(PetscPopErrorHandler());
  PetscCall(PetscSNPrintf(what, sizeof(what), "options %s: refused", opts));
  PetscCall(Check((PetscBool)(ierr == want), what, (PetscReal)ierr, (PetscReal)want));
  PetscCall(KergsPredictorDestroy(&p));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestOptions(void)
{
  PetscFunctionBeginUser;
  PetscCall(CheckError("-predictor_type linear -predictor_eta -1", PETSC_ERR_ARG_OUTOFRANGE));
  PetscCall(CheckError("-predictor_type linear -predictor_eta 0", PETSC_ERR_ARG_OUTOFRANGE));
  PetscCall(CheckError("-predictor_type elastic -predictor_epsilon -1e-3", PETSC_ERR_ARG_OUTOFRANGE));
  PetscCall(CheckError("-predictor_type unilateral -predictor_unilateral_tol 0", PETSC_ERR_ARG_OUTOFRANGE));
  PetscCall(CheckError("-predictor_type unilateral -predictor_unilateral_max_it 0", PETSC_ERR_ARG_OUTOFRANGE));
  PetscCall(CheckError("-predictor_type elastik", PETSC_ERR_ARG_UNKNOWN_TYPE));
  PetscFunctionReturn(0);
}

/* -help: every type's options (the test registration matches them). PETSc prints an options block once, so
   the type with its own options in that block (unilateral) comes first; linear brings the KSP's. */
static PetscErrorCode ShowHelp(void)
{
  const char    *types[] = {"unilateral", "linear", "elastic", "none"};
  KergsPredictor p;

  PetscFunctionBeginUser;
  for (PetscInt t = 0; t < 4; t++) {
    PetscCall(PetscOptionsSetValue(NULL, "-predictor_type", types[t]));
    PetscCall(KergsPredictorCreate(PETSC_COMM_WORLD, &p));
    PetscCall(KergsPredictorSetFromOptions(p));
    PetscCall(KergsPredictorView(p, PETSC_VIEWER_STDOUT_WORLD));
    PetscCall(KergsPredictorDestroy(&p));
  }
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscBool showhelp;

  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PetscOptionsHasHelp(NULL, &showhelp));
  if (showhelp) {
    PetscCall(ShowHelp());
    PetscCall(PetscFinalize());
    return 0;
  }
  PetscCall(TestColumn(0.0));
  PetscCall(TestColumn(0.3));
  PetscCall(TestSingleDisk(1.0, 0.0));
  PetscCall(TestSingleDisk(0.5, -0.02));
  PetscCall(TestInactive());
  PetscCall(TestLatticeRanks());
  PetscCall(TestOptions());
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
