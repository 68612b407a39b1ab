/* Physics with known answers, through the whole engine (scene -> detect -> operators -> NLGS -> update).
   Runs on 1 and 2 ranks; every check is global. */
static const char help[] =
    "kergs physics tests: column, slopes, wedged pair, momentum balance, adjoint of H, non-convergence, pressure wall, guided wall.\n";

#include "testing.h"

/* A column of N disks on a floor carries its cumulative weight: the contact below disk k carries
   (N - k) m g dt, with no tangential impulse, and nothing moves. */
static PetscErrorCode TestColumn(void)
{
  KergsStepper   st;
  const PetscInt N = 6;
  PetscReal      g = 10, dt = 1e-3, worst = 0, worst_t = 0, m, vmax, ek;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper("-gravity 0,-10 -friction 0.3 -dt 1e-3 -steps 12 -disks_source lattice -lattice_type square -lattice_n 1,6 "
                        "-lattice_radius 0.1 -lattice_origin 0,0.1 -walls floor -wall_floor_a -1,0 -wall_floor_b 1,0 -wall_floor_infinite "
                        "-alert 0.01 -solver_tol 1e-13 -solver_max_it 20000",
                        &st));
  m = PETSC_PI * 0.1 * 0.1; /* density 1 */
  for (PetscInt s = 0; s < 12; s++) {
    PetscReal xall[2 * N];
    PetscCall(KergsStepperStep(st));
    /* lattice gaps of +1e-17 leave contacts inactive (g~ > 0) until each disk has fallen for one step:
       the column is settled once every contact has been active for a step */
    if (s < N + 2) continue;
    PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->x, KERGS_DIM, xall));
    for (PetscInt k = 0; k < st->contacts->n; k++) {
      const KergsContact *c     = &st->contacts->c[k];
      PetscInt            above = 0; /* disks at or above the upper disk of the pair (all of them for the floor) */
      PetscReal ytop = c->kind == KERGS_CONTACT_DISK_WALL ? -1.0 : PetscMax(st->scene->x[2 * c->a + 1], st->scene->x[2 * c->b + 1]);
      PetscReal want;
      for (PetscInt i = 0; i < N; i++)
        if (xall[2 * i + 1] >= ytop - 1e-6) above++;
      want    = above * m * g * dt;
      worst   = PetscMax(worst, PetscAbsReal(c->r[0] - want) / (N * m * g * dt));
      worst_t = PetscMax(worst_t, PetscAbsReal(c->r[1]) / (N * m * g * dt));
    }
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &worst, 1, MPIU_REAL, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &worst_t, 1, MPIU_REAL, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(KergsSceneKineticEnergy(st->scene, &ek, &vmax));
  PetscCall(Check((PetscBool)(st->contacts->nglobal == N), "column: N contacts", (PetscReal)st->contacts->nglobal, N));
  PetscCall(Check((PetscBool)(worst < 1e-8), "column: normal impulse = weight above (relative error)", worst, 0));
  PetscCall(Check((PetscBool)(worst_t < 1e-8), "column: no tangential impulse", worst_t, 0));
  PetscCall(Check((PetscBool)(vmax < 1e-8), "column: at rest (fastest grain)", vmax, 0));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* One disk on an inclined line through the origin at angle alpha. Returns the disk's velocity along the
   slope (downhill positive) and its angular velocity after nsteps. */
static PetscErrorCode RunSlope(PetscReal alpha, PetscReal mu, PetscBool lock, PetscInt nsteps, PetscReal *vdown, PetscReal *vnormal,
                               PetscReal *omega, PetscReal *R)
{
  KergsStepper st;
  char         opts[1024];
  PetscReal    c = PetscCosReal(alpha), s = PetscSinReal(alpha), r = 0.1, d = r - 1e-9; /* start touching: gap -1e-9 */

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts),
                          "-gravity 0,-10 -friction %.17g -dt 1e-3 -steps %" PetscInt_FMT
                          " -disks_source list -disks_x %.17g,%.17g -disks_radius %g %s "
                          "-walls slope -wall_slope_a %.17g,%.17g -wall_slope_b %.17g,%.17g -wall_slope_infinite -alert 0.01 -solver_tol "
                          "1e-14 -solver_max_it 1000",
                          (double)mu, nsteps, (double)(-s * d), (double)(c * d), (double)r, lock ? "-disks_lock_rotation" : "",
                          (double)(-10 * c), (double)(-10 * s), (double)(10 * c), (double)(10 * s)));
  PetscCall(MakeStepper(opts, &st));
  for (PetscInt k = 0; k < nsteps; k++) PetscCall(KergsStepperStep(st));
  {
    PetscReal v[KERGS_DIM], w[KERGS_NROT]; /* the one disk, from whichever rank owns it */
    PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->v, KERGS_DIM, v));
    PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->omega, KERGS_NROT, w));
    *vdown   = -(v[0] * c + v[1] * s);
    *vnormal = -v[0] * s + v[1] * c;
    *omega   = w[0];
  }
  *R = r;
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestSlopes(void)
{
  const PetscInt  n = 50;
  const PetscReal g = 10, dt = 1e-3, mu = 0.5, T = n * dt;
  PetscReal       v, vn, w, R, alpha, want;

  PetscFunctionBeginUser;
  /* a block-like disk (rotation locked): sticks below tan(alpha) = mu, slides with g (sin - mu cos) above */
  alpha = PetscAtanReal(0.8 * mu);
  PetscCall(RunSlope(alpha, mu, PETSC_TRUE, n, &v, &vn, &w, &R));
  PetscCall(Check((PetscBool)(PetscAbsReal(v) < 1e-10), "slope, locked, tan = 0.8 mu: sticks (speed)", v, 0));
  alpha = PetscAtanReal(1.2 * mu);
  want  = g * (PetscSinReal(alpha) - mu * PetscCosReal(alpha)) * T;
  PetscCall(RunSlope(alpha, mu, PETSC_TRUE, n, &v, &vn, &w, &R));
  PetscCall(Check((PetscBool)(PetscAbsReal(v - want) < 1e-8 * want), "slope, locked, tan = 1.2 mu: slides at g(sin - mu cos)", v, want));
  PetscCall(Check((PetscBool)(PetscAbsReal(vn) < 1e-10), "slope, locked: stays on the slope (normal speed)", vn, 0));
  /* a free disk rolls without slipping for tan(alpha) < 3 mu: a = 2/3 g sin, and omega R = v */
  alpha = PetscAtanReal(2.0 * mu);
  want  = 2.0 / 3.0 * g * PetscSinReal(alpha) * T;
  PetscCall(RunSlope(alpha, mu, PETSC_FALSE, n, &v, &vn, &w, &R));
  PetscCall(Check((PetscBool)(PetscAbsReal(v - want) < 1e-8 * want), "slope, rolling, tan = 2 mu: a = 2/3 g sin", v, want));
  PetscCall(Check((PetscBool)(PetscAbsReal(PetscAbsReal(w) * R - v) < 1e-8 * want), "slope, rolling: |omega| R = v (no slip)",
                  PetscAbsReal(w) * R, v));
  /* above 3 mu it slips: a = g (sin - mu cos), angular acceleration 2 mu g cos / R */
  alpha = PetscAtanReal(4.0 * mu);
  want  = g * (PetscSinReal(alpha) - mu * PetscCosReal(alpha)) * T;
  PetscCall(RunSlope(alpha, mu, PETSC_FALSE, n, &v, &vn, &w, &R));
  PetscCall(Check((PetscBool)(PetscAbsReal(v - want) < 1e-8 * want), "slope, slipping, tan = 4 mu: a = g(sin - mu cos)", v, want));
  want = 2 * mu * g * PetscCosReal(alpha) / R * T;
  PetscCall(Check((PetscBool)(PetscAbsReal(PetscAbsReal(w) - want) < 1e-8 * want), "slope, slipping: |omega| = 2 mu g cos t / R",
                  PetscAbsReal(w), want));
  PetscFunctionReturn(0);
}

/* Sum over every rank's contacts of the impulses they put on each disk (force and torque),
   by global disk index. */
static PetscErrorCode DiskImpulses(KergsStepper st, PetscReal *P /* 3 per disk, global, summed over ranks */)
{
  KergsScene sc = st->scene;

  PetscFunctionBeginUser;
  PetscCall(PetscArrayzero(P, 3 * sc->ndisks));
  for (PetscInt k = 0; k < st->contacts->n; k++) {
    const KergsContact *c = &st->contacts->c[k];
    const PetscInt      a = sc->gidx[c->a];
    for (PetscInt d = 0; d < 2; d++) P[3 * a + d] += c->r[0] * c->n[d] + c->r[1] * c->t[d];
    P[3 * a + 2] += -c->ra * c->r[1];
    if (c->kind == KERGS_CONTACT_DISK_DISK) {
      const PetscInt b = sc->gidx[c->b];
      for (PetscInt d = 0; d < 2; d++) P[3 * b + d] -= c->r[0] * c->n[d] + c->r[1] * c->t[d];
      P[3 * b + 2] += -c->rb * c->r[1];
    }
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, P, 3 * sc->ndisks, MPIU_REAL, MPI_SUM, PETSC_COMM_WORLD));
  PetscFunctionReturn(0);
}

/* Two disks wedged in a channel come to rest with balanced forces: H r + R^d = 0 on every disk. */
static PetscErrorCode TestWedgedPair(void)
{
  KergsStepper st;
  PetscReal    P[6], vmax, ek, worst = 0, w, mass[2], radius[2];

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsClear(NULL));
  PetscCall(MakeStepper(
      "-options_file cases/two_disks_wedged.opts -wall_right_velocity 0,0 -steps 300 -solver_tol 1e-12 -solver_max_it 5000", &st));
  for (PetscInt k = 0; k < 300; k++) PetscCall(KergsStepperStep(st));
  PetscCall(KergsSceneKineticEnergy(st->scene, &ek, &vmax));
  PetscCall(DiskImpulses(st, P));
  PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->mass, 1, mass));
  PetscCall(KergsSceneAllGatherReal(st->scene, st->scene->radius, 1, radius));
  for (PetscInt i = 0; i < 2; i++) {
    w     = mass[i] * 9.81 * st->scene->dt;
    worst = PetscMax(worst, PetscAbsReal(P[3 * i + 0]) / w);
    worst = PetscMax(worst, PetscAbsReal(P[3 * i + 1] - w) / w);
    worst = PetscMax(worst, PetscAbsReal(P[3 * i + 2]) / (w * radius[i]));
  }
  PetscCall(Check((PetscBool)(vmax < 1e-6), "wedged pair: comes to rest (fastest grain)", vmax, 0));
  PetscCall(Check((PetscBool)(worst < 1e-6), "wedged pair: contact impulses balance the weight", worst, 0));
  PetscCall(Check((PetscBool)(st->contacts->nglobal == 4), "wedged pair: 4 contacts", (PetscReal)st->contacts->nglobal, 4));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* Momentum balance of every step: sum of m (V+ - V-) over disks = sum of R^d + impulses of the walls;
   contact impulses between disks cancel (action and reaction). */
static PetscErrorCode TestMomentumBalance(void)
{
  KergsStepper st;
  PetscReal   *vold, *P, worst = 0;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper("-gravity 0,-9.81 -friction 0.4 -dt 1e-3 -steps 40 -disks_source random -random_n 200 -random_box 0,0,0.6,0.8 "
                        "-random_radius 0.01,0.02 -box 0,0,0.6,1 -box_open_top -wall_box_right_velocity -0.1,0 -solver_max_it 50",
                        &st));
  PetscCall(PetscMalloc2(2 * st->scene->ndisks, &vold, 3 * st->scene->ndisks, &P));
  for (PetscInt s = 0; s < 40; s++) {
    PetscReal  sums[5] = {0, 0, 0, 0, 0}, *dP = sums, *ext = sums + 2; /* dP, ext, scale: over the owned disks, then all */
    KergsScene sc = st->scene;
    /* the velocities before the step, by grain id: a repartition may move disks between ranks during the step */
    PetscCall(GatherById(sc, sc->v, KERGS_DIM, vold));
    PetscCall(KergsStepperStep(st));
    PetscCall(DiskImpulses(st, P));
    for (PetscInt i = 0; i < sc->nowned; i++)
      for (PetscInt d = 0; d < 2; d++) {
        const PetscInt g = sc->dstart + i;
        dP[d] += sc->mass[i] * (sc->v[2 * i + d] - vold[2 * sc->id[i] + d]);
        ext[d] += P[3 * g + d] + sc->mass[i] * sc->gravity[d] * sc->dt;
        sums[4] += sc->mass[i] * 9.81 * sc->dt;
      }
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 5, MPIU_REAL, MPIU_SUM, PETSC_COMM_WORLD));
    const PetscReal scale = sums[4];
    worst                 = PetscMax(worst, (PetscAbsReal(dP[0] - ext[0]) + PetscAbsReal(dP[1] - ext[1])) / scale);
  }
  PetscCall(Check((PetscBool)(worst < 1e-12), "momentum balance per step (relative)", worst, 0));
  PetscCall(PetscFree2(vold, P));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* H^T assembled as a Mat agrees with the contact kinematics (v_n = n.(u_a - u_b),
   v_t = t.(u_a - u_b) - Ra w_a - Rb w_b) and H with the statics (force r_n n + r_t t, torque -Ra r_t on a,
   the opposite force and torque -Rb r_t on b); hence <H r, V> = <r, H^T V>. */
static PetscErrorCode TestAdjoint(void)
{
  KergsStepper       st;
  KergsOperators     ops;
  Vec                V, r, HtV, Hr;
  PetscRandom        rnd;
  VecScatter         all;
  Vec                Vall, Hrall;
  PetscReal          dot1, dot2, errv = 0, errf = 0, *P;
  const PetscScalar *va, *ra, *htv, *hr;
  PetscInt           nd;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper("-gravity 0,-9.81 -friction 0.4 -dt 1e-3 -steps 5 -disks_source random -random_n 300 -random_box 0,0,0.5,1.1 "
                        "-random_radius 0.01,0.02 -box 0,0,0.5,1.2 -box_open_top -alert 0.01",
                        &st));
  for (PetscInt s = 0; s < 5; s++) PetscCall(KergsStepperStep(st));
  PetscCall(KergsContactsDetect(st->contacts, st->scene));
  PetscCall(KergsOperatorsAssemble(st->ops, st->scene, st->contacts));
  ops = st->ops;
  nd  = ops->ndof_disk;
  PetscCall(Check((PetscBool)(nd == 3 && ops->ncomp == 2), "adjoint: frictional scene has rotations and tangents", nd, 3));
  PetscCall(PetscRandomCreate(PETSC_COMM_WORLD, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, -1, 1));
  PetscCall(VecDuplicate(ops->Vf, &V));
  PetscCall(VecDuplicate(ops->Vf, &Hr));
  PetscCall(VecDuplicate(ops->r, &r));
  PetscCall(VecDuplicate(ops->r, &HtV));
  PetscCall(VecSetRandom(V, rnd));
  PetscCall(VecSetRandom(r, rnd));
  PetscCall(MatMult(ops->HfT, V, HtV));
  PetscCall(MatMultTranspose(ops->HfT, r, Hr));
  PetscCall(VecDot(Hr, V, &dot1));
  PetscCall(VecDot(r, HtV, &dot2));
  PetscCall(Check((PetscBool)(PetscAbsReal(dot1 - dot2) < 1e-12 * PetscAbsReal(dot1)), "adjoint: <H r, V> = <r, H^T V>", dot1, dot2));
  /* kinematics, contact by contact, against the Mat */
  PetscCall(VecScatterCreateToAll(V, &all, &Vall));
  PetscCall(VecScatterBegin(all, V, Vall, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(all, V, Vall, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecDuplicate(Vall, &Hrall));
  PetscCall(VecScatterBegin(all, Hr, Hrall, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(all, Hr, Hrall, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetArrayRead(Vall, &va));
  PetscCall(VecGetArrayRead(r, &ra));
  PetscCall(VecGetArrayRead(HtV, &htv));
  PetscCall(VecGetArrayRead(Hrall, &hr));
  PetscCall(PetscCalloc1(3 * st->scene->ndisks, &P));
  for (PetscInt k = 0; k < st->contacts->n; k++) {
    const KergsContact *c = &st->contacts->c[k];
    const PetscInt      a = st->scene->gidx[c->a], b = c->kind == KERGS_CONTACT_DISK_DISK ? st->scene->gidx[c->b] : -1;
    const PetscScalar  *ua = &va[a * nd], *ub = b >= 0 ? &va[b * nd] : NULL;
    PetscReal           du[2], wb             = ub ? ub[2] : 0, vn, vt;
    for (PetscInt d = 0; d < 2; d++) du[d] = ua[d] - (ub ? ub[d] : 0); /* walls are at rest here: driven, V_g not in V_f */
    vn   = c->n[0] * du[0] + c->n[1] * du[1];
    vt   = c->t[0] * du[0] + c->t[1] * du[1] - c->ra * ua[2] - c->rb * wb;
    errv = PetscMax(errv, PetscAbsReal(vn - htv[2 * k]) + PetscAbsReal(vt - htv[2 * k + 1]));
    for (PetscInt d = 0; d < 2; d++) P[3 * a + d] += ra[2 * k] * c->n[d] + ra[2 * k + 1] * c->t[d];
    P[3 * a + 2] -= c->ra * ra[2 * k + 1];
    if (ub) {
      for (PetscInt d = 0; d < 2; d++) P[3 * b + d] -= ra[2 * k] * c->n[d] + ra[2 * k + 1] * c->t[d];
      P[3 * b + 2] -= c->rb * ra[2 * k + 1];
    }
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, P, 3 * st->scene->ndisks, MPIU_REAL, MPI_SUM, PETSC_COMM_WORLD));
  for (PetscInt i = 0; i < 3 * st->scene->ndisks; i++) errf = PetscMax(errf, PetscAbsReal(P[i] - hr[i]));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &errv, 1, MPIU_REAL, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(Check((PetscBool)(errv < 1e-13), "adjoint: H^T V matches the contact kinematics", errv, 0));
  PetscCall(Check((PetscBool)(errf < 1e-13), "adjoint: H r matches the contact statics", errf, 0));
  PetscCall(VecRestoreArrayRead(Vall, &va));
  PetscCall(VecRestoreArrayRead(r, &ra));
  PetscCall(VecRestoreArrayRead(HtV, &htv));
  PetscCall(VecRestoreArrayRead(Hrall, &hr));
  PetscCall(PetscFree(P));
  PetscCall(VecScatterDestroy(&all));
  PetscCall(VecDestroy(&Vall));
  PetscCall(VecDestroy(&Hrall));
  PetscCall(VecDestroy(&V));
  PetscCall(VecDestroy(&Hr));
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&HtV));
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* The straight row of confine5 has no solution at velocity level: every solve must report non-convergence,
   and the interpenetration stays within the right wall's displacement (NLGS's answers applied all the same:
   -on_infeasible continue). By default the run stops at the first step proved infeasible, with status 5, NLGS's
   runaway impulses proving it at step 18 (measured). */
static PetscErrorCode TestInfeasibleRow(void)
{
  KergsStepper st;
  PetscReal    disp, mean, nactive;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper("-options_file cases/confine5_straight.opts", &st));
  PetscCall(KergsStepperRun(st));
  PetscCall(Check((PetscBool)(st->status == KERGS_EXIT_SOLVER_FAILED && st->scene->step < st->scene->nsteps),
                  "straight row: the run stops at a step proved infeasible (status 5)", st->status, KERGS_EXIT_SOLVER_FAILED));
  PetscCall(KergsStepperDestroy(&st));
  PetscCall(MakeStepper("-options_file cases/confine5_straight.opts -on_infeasible continue", &st));
  PetscCall(KergsStepperRun(st));
  disp = 0;
  for (PetscInt w = 0; w < st->scene->nwalls; w++) {
    PetscBool right;
    PetscCall(PetscStrcmp(st->scene->walls[w].name, "right", &right));
    if (right) disp = PetscAbsReal(st->scene->walls[w].disp[0]);
  }
  PetscCall(Check((PetscBool)(st->nonconverged == st->scene->nsteps), "straight row: every solve reports non-convergence", st->nonconverged,
                  st->scene->nsteps));
  PetscCall(Check((PetscBool)(st->max_violation <= disp + 1e-12), "straight row: interpenetration <= wall displacement", st->max_violation,
                  disp));
  PetscCall(StatAt(st->results, "mean_violation", -1, &mean));
  PetscCall(StatAt(st->results, "active", -1, &nactive));
  /* the wall's travel is shared among the contacts of the row: their interpenetrations add up to it */
  PetscCall(Check((PetscBool)(mean * nactive > 0.5 * disp && mean * nactive <= disp + 1e-12),
                  "straight row: the wall's motion became interpenetration", mean * nactive, disp));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* A solve that says it converged under the natural criterion has its natural-map residual below the tolerance. The
   residual is recomputed by the test from the impulses the step left (IndependentNaturalResidual: W r + v^d and the
   projection on the Coulomb cone written in tests/testing.h), not read back from the statistic the library computed
   and decided with: the library's residual routine, its convergence decision and its recorded `residual` are all
   under test. -keep_H keeps W after the step (the trajectory is the same to the bit, TestKeepH). */
static PetscErrorCode TestConvergedResidual(void)
{
  KergsStepper    st;
  const PetscReal tol = 1e-9;
  PetscReal       conv, recorded, res, nconv = 0, worst_conv = 0, worst_diff = 0, nlying = 0, ndiffer = 0;

  PetscFunctionBeginUser;
  /* static walls: with the right wall squeezing, the frictional wedge jams and NLGS rightly reports failure */
  PetscCall(MakeStepper("-options_file cases/two_disks_wedged.opts -wall_right_velocity 0,0 -steps 20 -solver_criterion natural "
                        "-solver_tol 1e-9 -solver_max_it 10000 -keep_H",
                        &st));
  for (PetscInt s = 0; s < 20; s++) {
    PetscCall(KergsStepperStep(st));
    PetscCall(StatAt(st->results, "converged", -1, &conv));
    PetscCall(StatAt(st->results, "residual", -1, &recorded));
    PetscCall(IndependentNaturalResidual(st, &res));
    /* the same quantity up to rounding: summation orders differ, and the residual is relative to |r| */
    if (!(PetscAbsReal(recorded - res) <= 1e-6 * res + 1e-13)) ndiffer++;
    worst_diff = PetscMax(worst_diff, PetscAbsReal(recorded - res));
    if (conv > 0.5) {
      nconv++;
      worst_conv = PetscMax(worst_conv, res);
      if (!(res < tol)) nlying++;
    }
  }
  PetscCall(Check((PetscBool)(nlying == 0), "static wedged pair: every step said converged has natural residual < tol (recomputed)",
                  worst_conv, tol));
  PetscCall(Check((PetscBool)(ndiffer == 0), "static wedged pair: recorded residual = recomputed one (largest difference)", worst_diff, 0));
  /* most steps converge (a step where one contact is momentarily open stalls near 5e-9 and says so) */
  PetscCall(Check((PetscBool)(nconv >= 15), "static wedged pair: steps converged", nconv, 20));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* W assembled body by body (each rank adds its own disks' terms, rows of other ranks' contacts through the stash,
   a free wall's terms from the gathered list of its contacts) equals PETSc's product H_f^T M^-1 H_f, entry by entry
   and with the same pattern. A frictional deposit pushed by a free wall under a constant force, guided (its rows of
   H_f projected on its normal), on 1, 2 ranks. W with both triangles (KergsOperatorsSetBothTriangles), assembled
   directly on several ranks, equals the conversion of the upper triangle (to rounding: on several ranks the diagonal
   blocks that receive another rank's term differ in their off-diagonal entries, 1e-18 relative), over all pairs and
   over the active contacts, with exact preallocation. */
static PetscErrorCode TestDelassusAssembly(void)
{
  KergsStepper   st;
  KergsOperators ops;
  Mat            MinvHf, Wref, Waij;
  PetscReal      nref, ndiff;
  MatInfo        iw, ir;

  PetscFunctionBeginUser;
  /* NLGS under the paper's gap rule: some potential contacts stay inactive */
  PetscCall(MakeStepper("-solver_type nlgs -solver_criterion quad -solver_tol 1e-4 -gap_rule paper "
                        "-gravity 0,-9.81 -friction 0.4 -dt 1e-3 -disks_source random -random_n 200 -random_box 0,0,0.5,0.8 "
                        "-random_radius 0.018,0.02 -box 0,0,0.5,1 -box_open_top -alert 0.01 -walls piston -wall_piston_a 0.5,0.685 "
                        "-wall_piston_b 0,0.685 -wall_piston_type free -wall_piston_mass 0.5 -wall_piston_force 0,-5 -wall_piston_guided "
                        "-solver_max_it 50",
                        &st));
  for (PetscInt s = 0; s < 30; s++) PetscCall(KergsStepperStep(st));
  PetscCall(KergsContactsDetect(st->contacts, st->scene));
  PetscCall(KergsOperatorsAssemble(st->ops, st->scene, st->contacts));
  ops = st->ops;
  PetscCall(MatTranspose(ops->HfT, MAT_INITIAL_MATRIX, &MinvHf));
  PetscCall(MatDiagonalScale(MinvHf, ops->Minv, NULL));
  PetscCall(MatMatMult(ops->HfT, MinvHf, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Wref));
  /* W is stored by its upper block triangle (SBAIJ): the conversion writes both triangles */
  PetscCall(MatConvert(ops->W, MATAIJ, MAT_INITIAL_MATRIX, &Waij));
  PetscCall(MatGetInfo(Waij, MAT_GLOBAL_SUM, &iw));
  {
    MatInfo   is;
    PetscInt  N, bs;
    PetscBool upper;
    PetscCall(MatGetInfo(ops->W, MAT_GLOBAL_SUM, &is));
    PetscCall(MatGetSize(ops->W, &N, NULL));
    PetscCall(MatGetBlockSize(ops->W, &bs));
    PetscCall(PetscObjectTypeCompareAny((PetscObject)ops->W, &upper, MATSEQSBAIJ, MATMPISBAIJ, ""));
    PetscCall(Check((PetscBool)(upper && 2 * is.nz_used - N * bs == iw.nz_used),
                    "W by bodies: upper block triangle stored (2 stored - diagonal blocks = whole)", 2 * is.nz_used - N * bs, iw.nz_used));
  }
  PetscCall(MatGetInfo(Wref, MAT_GLOBAL_SUM, &ir));
  PetscCall(MatNorm(Wref, NORM_FROBENIUS, &nref));
  PetscCall(MatAXPY(Wref, -1.0, Waij, DIFFERENT_NONZERO_PATTERN));
  PetscCall(MatNorm(Wref, NORM_FROBENIUS, &ndiff));
  {
    PetscInt atwall = 0; /* contacts at the free wall, all ranks */
    for (PetscInt k = 0; k < st->contacts->n; k++)
      atwall += st->contacts->c[k].kind == KERGS_CONTACT_DISK_WALL && st->scene->walls[st->contacts->c[k].b].kind == KERGS_WALL_FREE;
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &atwall, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
    PetscCall(Check((PetscBool)(ops->nfreewalls == 1 && atwall >= 5 && st->contacts->nglobal > 100),
                    "W by bodies: contacts at the free wall", (PetscReal)atwall, 5));
  }
  PetscCall(Check((PetscBool)(ndiff <= 1e-14 * nref), "W by bodies = H_f^T M^-1 H_f (relative Frobenius)", ndiff / nref, 0));
  PetscCall(Check((PetscBool)(iw.nz_used == ir.nz_used), "W by bodies: same pattern as the product (nonzeros)", iw.nz_used, ir.nz_used));
  for (PetscInt active = 0; active < 2; active++) { /* with both triangles (the readers of whole rows), over all pairs
                                                      and over the active contacts, assembled so on several ranks */
    Mat         Wfull, Wconv;
    MatInfo     ib, ic;
    PetscReal   nconv, nd;
    PetscMPIInt size;
    PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
    PetscCall(KergsOperatorsSetBothTriangles(ops, PETSC_TRUE));
    PetscCall(KergsOperatorsAssembleW(ops, st->scene, st->contacts, (PetscBool)active));
    PetscCall(MatConvert(ops->W, MATAIJ, MAT_INITIAL_MATRIX, &Wconv));
    PetscCall(KergsOperatorsGetFullW(ops, &Wfull));
    PetscCall(Check((PetscBool)((size > 1) == (Wfull == ops->Wboth)), "W with both triangles: assembled on several ranks, converted on one",
                    (PetscReal)(Wfull == ops->Wboth), (PetscReal)(size > 1)));
    PetscCall(MatGetInfo(Wfull, MAT_GLOBAL_SUM, &ib));
    PetscCall(MatGetInfo(Wconv, MAT_GLOBAL_SUM, &ic));
    PetscCall(MatNorm(Wconv, NORM_FROBENIUS, &nconv));
    PetscCall(MatAXPY(Wconv, -1.0, Wfull, DIFFERENT_NONZERO_PATTERN));
    PetscCall(MatNorm(Wconv, NORM_FROBENIUS, &nd));
    PetscCall(Check((PetscBool)(nd <= 1e-15 * nconv && ib.nz_used == ic.nz_used && ib.nz_allocated == ib.nz_used),
                    active ? "... over the active contacts too"
                           : "W with both triangles = W's upper triangle converted (relative "
                             "Frobenius; the same nonzeros, exactly preallocated)",
                    nd / nconv, 1e-15));
    PetscCall(MatDestroy(&Wfull));
    PetscCall(MatDestroy(&Wconv));
    PetscCall(KergsOperatorsSetBothTriangles(ops, PETSC_FALSE));
  }
  PetscCall(MatDestroy(&MinvHf));
  PetscCall(MatDestroy(&Wref));
  PetscCall(MatDestroy(&Waij));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* The time step frees H before W is assembled and builds H_f again for the update (peak memory max(H, W)), unless
   -keep_H: both ways give the same trajectory to the bit, with a driven box (H_g) and a free piston. */
static PetscErrorCode TestKeepH(void)
{
  const char  *opts = "-gravity 0,-9.81 -friction 0.4 -dt 1e-3 -disks_source random -random_n 200 -random_box 0,0,0.5,0.8 "
                      "-random_radius 0.018,0.02 -box 0,0,0.5,1 -box_open_top -alert 0.01 -walls piston -wall_piston_a 0.5,0.685 "
                      "-wall_piston_b 0,0.685 -wall_piston_type free -wall_piston_mass 0.5 -wall_piston_force 0,-5 -solver_max_it 50";
  KergsStepper st[2];
  PetscReal   *state[2], diff = 0, nnz[2][2];
  PetscBool    released[2];
  char         both[1024];

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < 2; k++) {
    KergsScene sc;
    PetscReal *owned;
    PetscCall(PetscSNPrintf(both, sizeof(both), "%s%s", opts, k ? " -keep_H" : ""));
    PetscCall(MakeStepper(both, &st[k]));
    for (PetscInt s = 0; s < 20; s++) PetscCall(KergsStepperStep(st[k]));
    sc          = st[k]->scene;
    released[k] = (PetscBool)(st[k]->ops->W == NULL);
    nnz[k][0]   = st[k]->ops->nnz_Hf;
    nnz[k][1]   = st[k]->ops->nnz_W;
    PetscCall(PetscMalloc1(5 * sc->nowned + 1, &owned));
    PetscCall(PetscMalloc1(5 * sc->ndisks, &state[k]));
    for (PetscInt i = 0; i < sc->nowned; i++) {
      for (PetscInt d = 0; d < KERGS_DIM; d++) owned[5 * i + d] = sc->x[KERGS_DIM * i + d];
      for (PetscInt d = 0; d < KERGS_DIM; d++) owned[5 * i + KERGS_DIM + d] = sc->v[KERGS_DIM * i + d];
      owned[5 * i + 4] = sc->omega[i];
    }
    PetscCall(GatherById(sc, owned, 5, state[k]));
    PetscCall(PetscFree(owned));
  }
  for (PetscInt i = 0; i < 5 * st[0]->scene->ndisks; i++) diff = PetscMax(diff, PetscAbsReal(state[0][i] - state[1][i]));
  PetscCall(Check((PetscBool)(released[0] && !released[1]), "keep_H: W released before the update by default, kept with -keep_H",
                  released[0], 1));
  PetscCall(Check((PetscBool)(diff == 0.0), "keep_H: same positions, velocities, spins to the bit", diff, 0));
  PetscCall(Check((PetscBool)(nnz[0][0] == nnz[1][0] && nnz[0][1] == nnz[1][1] && nnz[0][1] > 0),
                  "keep_H: same nonzeros of H_f and W recorded", nnz[0][1], nnz[1][1]));
  for (PetscInt k = 0; k < 2; k++) {
    PetscCall(PetscFree(state[k]));
    PetscCall(KergsStepperDestroy(&st[k]));
  }
  PetscFunctionReturn(0);
}

/* W over the active contacts only (what the time step assembles for NLGS) against W over all pairs: the solve gives
   the same impulses to the bit from the same warm start, with fewer stored blocks. */
static PetscErrorCode TestActiveOnlyW(void)
{
  KergsStepper    st;
  KergsOperators  ops;
  KergsSolveStats ss[2];
  Vec             r[2];
  PetscReal       nnz[2], diff;
  PetscInt        nactive = 0;

  PetscFunctionBeginUser;
  /* NLGS under the paper's gap rule: some potential contacts stay inactive */
  PetscCall(MakeStepper("-solver_type nlgs -solver_criterion quad -solver_tol 1e-4 -gap_rule paper "
                        "-gravity 0,-9.81 -friction 0.4 -dt 1e-3 -disks_source random -random_n 200 -random_box 0,0,0.5,0.8 "
                        "-random_radius 0.018,0.02 -box 0,0,0.5,1 -box_open_top -alert 0.01 -walls piston -wall_piston_a 0.5,0.685 "
                        "-wall_piston_b 0,0.685 -wall_piston_type free -wall_piston_mass 0.5 -wall_piston_force 0,-5 -solver_max_it 50",
                        &st));
  for (PetscInt s = 0; s < 150; s++) PetscCall(KergsStepperStep(st)); /* settled under the piston */
  ops = st->ops;
  PetscCall(KergsContactsDetect(st->contacts, st->scene));
  PetscCall(KergsOperatorsAssembleH(ops, st->scene, st->contacts, PETSC_FALSE));
  for (PetscInt k = 0; k < 2; k++) {
    PetscCall(KergsOperatorsAssembleW(ops, st->scene, st->contacts, (PetscBool)(k == 0)));
    nnz[k] = ops->nnz_W;
    PetscCall(KergsOperatorsGetImpulses(ops, st->contacts)); /* the same warm start */
    PetscCall(KergsSolverSolve(st->solver, st->scene, st->contacts, ops, &ss[k]));
    PetscCall(VecDuplicate(ops->r, &r[k]));
    PetscCall(VecCopy(ops->r, r[k]));
  }
  {
    KergsActivity act;
    PetscCall(KergsContactsGetActivity(st->contacts, st->scene, &act));
    for (PetscInt k = 0; k < st->contacts->n; k++) nactive += KergsContactIsActive(&act, &st->contacts->c[k]);
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &nactive, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  PetscCall(VecAXPY(r[1], -1.0, r[0]));
  PetscCall(VecNorm(r[1], NORM_INFINITY, &diff));
  PetscCall(Check((PetscBool)(nactive > 20 && nactive < st->contacts->nglobal), "active-only W: some potential contacts are inactive",
                  nactive, st->contacts->nglobal));
  PetscCall(Check((PetscBool)(nnz[0] < nnz[1]), "active-only W: fewer nonzeros than W over all pairs", nnz[0], nnz[1]));
  PetscCall(Check((PetscBool)(diff == 0.0 && ss[0].iterations == ss[1].iterations && ss[0].residual == ss[1].residual),
                  "active-only W: same impulses to the bit, same sweeps and residual", diff, 0));
  PetscCall(VecDestroy(&r[0]));
  PetscCall(VecDestroy(&r[1]));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* Normal impulse of the step on wall w, summed over every rank's contacts. */
static PetscErrorCode WallImpulse(KergsStepper st, PetscInt w, PetscReal *rn)
{
  PetscFunctionBeginUser;
  *rn = 0;
  for (PetscInt k = 0; k < st->contacts->n; k++)
    if (st->contacts->c[k].kind == KERGS_CONTACT_DISK_WALL && st->contacts->c[k].b == w) *rn += st->contacts->c[k].r[0];
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, rn, 1, MPIU_REAL, MPIU_SUM, PETSC_COMM_WORLD));
  PetscFunctionReturn(0);
}

/* A pressure-controlled wall: without gravity, box_right under pressure p presses a row of three disks against
   box_left. At rest, its contact impulse over a step is p L dt, L the separation of box_bottom and box_top at the
   step's start; box_top then moves down by 0.1 (at 10 m/s on [0.02, 0.03)) without touching the row, and the force
   follows, to 0.9 p dt once it stops. The rigid row makes the answer exact: only the solver's tolerance is left. */
static PetscErrorCode TestPressureWall(void)
{
  const PetscReal p = 10, dt = 1e-3;
  KergsStepper    st;
  PetscReal       worst = 0, first = 0, last = 0, ek, vmax;

  PetscFunctionBeginUser;
  PetscCall(MakeStepper("-gravity 0,0 -friction 0.3 -dt 1e-3 -disks_source lattice -lattice_type square -lattice_n 3,1 "
                        "-lattice_radius 0.1 -lattice_origin 0.1,0.5 -box 0,0,0.6,1 -wall_box_right_type free -wall_box_right_mass 1 "
                        "-wall_box_right_pressure 10 -wall_box_top_program 0.02,0,-10,0.03,0,0 -alert 0.01 -solver_tol 1e-13 "
                        "-solver_max_it 20000",
                        &st));
  for (PetscInt s = 0; s < 40; s++) {
    const KergsWall *walls = st->scene->walls;
    const PetscReal  L     = walls[2].a[1] - walls[0].a[1]; /* box_top above box_bottom, at the step's start */
    PetscReal        rn;

    PetscCall(KergsStepperStep(st));
    PetscCall(WallImpulse(st, 1, &rn));
    if (s < 5) continue; /* the lattice's rounding gaps close in the first steps */
    worst = PetscMax(worst, PetscAbsReal(rn - p * L * dt) / (p * dt));
    if (s == 5) first = rn;
    last = rn;
  }
  PetscCall(KergsSceneKineticEnergy(st->scene, &ek, &vmax));
  PetscCall(Check((PetscBool)(worst < 1e-8), "pressure wall: impulse = p x (box_top - box_bottom) x dt every step (relative)", worst, 0));
  PetscCall(
      Check((PetscBool)(PetscAbsReal(first - p * dt) < 1e-8 * p * dt), "pressure wall: p x 1 x dt before box_top moves", first / dt, p));
  PetscCall(Check((PetscBool)(PetscAbsReal(last / first - 0.9) < 1e-8), "pressure wall: the force shrinks with the length (0.9)",
                  last / first, 0.9));
  PetscCall(Check((PetscBool)(vmax < 1e-8 && PetscAbsReal(st->scene->walls[1].v[0]) < 1e-8), "pressure wall: the row and the wall at rest",
                  PetscMax(vmax, PetscAbsReal(st->scene->walls[1].v[0])), 0));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* A guided wall (the default under a pressure) moves along its normal only. Under gravity g one disk of mass m slides
   down between box_left (fixed) and box_right (pressure p over the box's height 1, so a normal force p), both with
   friction mu: each wall holds it up by mu p, so v_y = -k dt (g - 2 mu p / m) after k steps, and box_right stays on
   its guide (v_y and its vertical displacement exactly zero). A wall free to slide along itself (-guided false) is
   dragged down: with box_right's mass 1e-3, mu p / M = 60 m/s^2 > g, it follows the disk and the disk falls faster. */
static PetscErrorCode RunGuidedWall(const char *guided, PetscReal *vdisk, PetscReal *vwall, PetscReal *ywall)
{
  char         opts[1024];
  KergsStepper st;
  PetscReal    v = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts),
                          "-gravity 0,-10 -friction 0.3 -dt 1e-3 -material_density 1 -disks_source lattice -lattice_type square "
                          "-lattice_n 1,1 -lattice_radius 0.1 -lattice_origin 0.1,0.5 -box 0,0,0.2,1 -wall_box_right_type free "
                          "-wall_box_right_mass 1e-3 -wall_box_right_pressure 0.2 -alert 0.01 -solver_tol 1e-13 -solver_max_it 20000 %s",
                          guided));
  PetscCall(MakeStepper(opts, &st));
  for (PetscInt s = 0; s < 20; s++) PetscCall(KergsStepperStep(st));
  if (st->scene->nowned) v = st->scene->v[1];
  PetscCall(MPIU_Allreduce(&v, vdisk, 1, MPIU_REAL, MPIU_SUM, PETSC_COMM_WORLD));
  *vwall = st->scene->walls[1].v[1];
  *ywall = st->scene->walls[1].disp[1];
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestGuidedWall(void)
{
  const PetscReal m = PETSC_PI * 0.01, expect = -20 * 1e-3 * (10 - 2 * 0.3 * 0.2 / m);
  PetscReal       vdisk, vwall, ywall;

  PetscFunctionBeginUser;
  PetscCall(RunGuidedWall("", &vdisk, &vwall, &ywall));
  PetscCall(
      Check((PetscBool)(PetscAbsReal(vdisk / expect - 1) < 1e-8), "guided wall: the disk slides down at g - 2 mu p / m", vdisk, expect));
  PetscCall(Check((PetscBool)(vwall == 0 && ywall == 0), "guided wall: box_right stays on its guide (v_y, displacement)",
                  PetscMax(PetscAbsReal(vwall), PetscAbsReal(ywall)), 0));
  PetscCall(RunGuidedWall("-wall_box_right_guided false", &vdisk, &vwall, &ywall));
  PetscCall(Check((PetscBool)(vwall < -0.1 && vdisk < expect * 1.05), "unguided wall: friction drags box_right down, the disk falls faster",
                  vwall, vdisk));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCall(TestColumn());
  PetscCall(TestSlopes());
  PetscCall(TestWedgedPair());
  PetscCall(TestMomentumBalance());
  PetscCall(TestAdjoint());
  PetscCall(TestDelassusAssembly());
  PetscCall(TestKeepH());
  PetscCall(TestActiveOnlyW());
  PetscCall(TestInfeasibleRow());
  PetscCall(TestConvergedResidual());
  PetscCall(TestPressureWall());
  PetscCall(TestGuidedWall());
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
