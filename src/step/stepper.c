/* kergs stepper: the time loop of Algorithm 1 (Moreau-Jean, theta-method). Data flows one way per step:
   scene state -> detect -> operators -> solver -> update -> results. */
#include <kergs/stepper.h>
#include <kergs/sample.h>
#include <kergs/fclib.h>
#include <sys/resource.h>

/* Peak resident memory of the whole run so far, in bytes, summed over ranks. */
static PetscErrorCode PeakMemory(MPI_Comm comm, PetscReal *bytes)
{
  struct rusage ru;
  PetscReal     mine;

  PetscFunctionBeginUser;
  getrusage(RUSAGE_SELF, &ru);
  mine = 1024.0 * (PetscReal)ru.ru_maxrss; /* Linux reports kilobytes */
  PetscCall(MPIU_Allreduce(&mine, bytes, 1, MPIU_REAL, MPI_SUM, comm));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperCreate(MPI_Comm comm, KergsStepper *stepper)
{
  KergsStepper st;

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscNew(&st));
  st->comm        = comm;
  st->fclib_step  = -1;
  st->overlap_tol = 5e-2; /* a settled NSCD sample keeps interpenetrations of about 1% of a radius */
  PetscCall(PeakMemory(comm, &st->baseline_rss));
  PetscCall(KergsSceneCreate(comm, &st->scene));
  PetscCall(KergsContactsCreate(comm, &st->contacts));
  PetscCall(KergsOperatorsCreate(comm, &st->ops));
  PetscCall(KergsSolverCreate(comm, &st->solver));
  PetscCall(KergsResultsCreate(comm, &st->results));
  PetscCall(KergsPartitionCreate(comm, &st->partition));
  *stepper = st;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperSetFromOptions(KergsStepper st)
{
  PetscFunctionBeginUser;
  PetscCall(KergsSceneSetFromOptions(st->scene));
  PetscCall(KergsSolverSetFromOptions(st->solver));
  PetscCall(KergsResultsSetSceneName(st->results, st->scene->name)); /* default -output: results/<scene>.h5 */
  PetscCall(KergsResultsSetFromOptions(st->results));
  PetscCall(KergsPartitionSetFromOptions(st->partition));
  PetscOptionsBegin(st->comm, NULL, "Time stepping options", NULL);
  PetscCall(PetscOptionsReal("-stop_at_rest", "Stop once every disk is slower than this speed, after the packing has moved faster (0: run all -steps)", "", st->rest_speed, &st->rest_speed, NULL));
  PetscCall(PetscOptionsString("-sample_output", "Write the final packing to this sample file (HDF5), for -disks_source file", "", st->sample_out, st->sample_out, sizeof(st->sample_out), NULL));
  PetscCall(PetscOptionsInt("-fclib_step", "Export the local problem of this step in FCLib format (-1: none)", "", st->fclib_step, &st->fclib_step, NULL));
  PetscCall(PetscOptionsString("-fclib_output", "FCLib file of -fclib_step", "", st->fclib_path, st->fclib_path, sizeof(st->fclib_path), NULL));
  PetscCall(PetscOptionsReal("-initial_overlap_tol", "Largest initial interpenetration allowed, relative to the smaller radius of the pair", "", st->overlap_tol, &st->overlap_tol, NULL));
  PetscCall(PetscOptionsBool("-quiet", "Do not print a summary line per step", "", st->quiet, &st->quiet, NULL));
  PetscCall(PetscOptionsBool("-keep_H", "Keep H_f and H_g through the solve, next to W (default: freed before W is assembled and H_f assembled again for the velocity update, so that the peak memory is the larger of H and W, not their sum; solvers that use H keep it anyway)", "", st->keep_H, &st->keep_H, NULL));
  PetscOptionsEnd();
  PetscCheck(st->rest_speed >= 0 && !PetscIsInfOrNanReal(st->rest_speed), st->comm, PETSC_ERR_ARG_OUTOFRANGE, "-stop_at_rest %g must be a non-negative speed", (double)st->rest_speed);
  PetscCheck(st->overlap_tol >= 0, st->comm, PETSC_ERR_ARG_OUTOFRANGE, "-initial_overlap_tol %g must be non-negative", (double)st->overlap_tol);
  if (st->fclib_step >= 0 && !st->fclib_path[0]) PetscCall(PetscSNPrintf(st->fclib_path, sizeof(st->fclib_path), "results/%s-step%" PetscInt_FMT ".fclib.h5", st->scene->name[0] ? st->scene->name : "kergs", st->fclib_step));
  PetscFunctionReturn(0);
}

/* Initial grains must not overlap (beyond a tolerance): report the first offending pair by grain id. */
static PetscErrorCode CheckInitialOverlaps(KergsStepper st)
{
  KergsScene    sc = st->scene;
  KergsContacts ct = st->contacts;
  PetscInt      bad = -1, nbad;

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < ct->n && bad < 0; k++) {
    const KergsContact *c    = &ct->c[k];
    PetscReal           rmin = c->kind == KERGS_CONTACT_DISK_DISK ? PetscMin(c->ra, c->rb) : c->ra;
    if (c->gap < -st->overlap_tol * rmin) bad = k;
  }
  PetscCall(MPIU_Allreduce(bad >= 0 ? &(PetscInt){1} : &(PetscInt){0}, &nbad, 1, MPIU_INT, MPI_SUM, st->comm));
  if (bad >= 0) {
    const KergsContact *c = &ct->c[bad];
    if (c->kind == KERGS_CONTACT_DISK_DISK)
      PetscCall(PetscPrintf(PETSC_COMM_SELF, "[kergs] grains %" PetscInt_FMT " and %" PetscInt_FMT " overlap by %g (radii %g, %g)\n", sc->id[c->a], sc->id[c->b], (double)-c->gap, (double)c->ra, (double)c->rb));
    else PetscCall(PetscPrintf(PETSC_COMM_SELF, "[kergs] grain %" PetscInt_FMT " crosses wall %s by %g (radius %g)\n", sc->id[c->a], sc->walls[c->b].name, (double)-c->gap, (double)c->ra));
  }
  PetscCheck(nbad == 0, st->comm, PETSC_ERR_USER_INPUT, "The initial packing has overlapping grains (see the pairs printed above); raise -initial_overlap_tol to accept interpenetrations up to that fraction of the smaller radius");
  PetscFunctionReturn(0);
}

/* x+ = x- + dt (theta V+ + (1 - theta) V-) for the owned disks and the walls; V- is given as the velocities before
   the update. */
static PetscErrorCode UpdatePositions(KergsScene sc, const PetscReal *vold, const PetscReal *wold, const PetscReal *wvold)
{
  PetscReal th = sc->theta, dt = sc->dt;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < KERGS_DIM * sc->nowned; i++) sc->x[i] += dt * (th * sc->v[i] + (1 - th) * vold[i]);
  for (PetscInt i = 0; i < KERGS_NROT * sc->nowned; i++) sc->rot[i] += dt * (th * sc->omega[i] + (1 - th) * wold[i]);
  for (PetscInt w = 0; w < sc->nwalls; w++) {
    KergsWall *wall = &sc->walls[w];
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      /* a driven wall moves with its given velocity; a free wall with the theta-rule like a disk */
      PetscReal dx = wall->kind == KERGS_WALL_DRIVEN ? dt * wall->v[d] : dt * (th * wall->v[d] + (1 - th) * wvold[KERGS_DIM * w + d]);
      wall->a[d] += dx;
      wall->b[d] += dx;
      wall->disp[d] += dx;
    }
  }
  PetscFunctionReturn(0);
}

/* Interpenetration at the end of the step, from the exact gaps of this step's contact pairs at the new
   positions: mean over active contacts of max(0, -g+), and the largest. Global. */
static PetscErrorCode MeasureViolation(KergsStepper st, PetscReal *mean, PetscReal *max, PetscInt *nactive)
{
  KergsScene sc = st->scene;
  PetscReal  loc[2] = {0, 0}, glob[2], lmax = 0, gmax;
  PetscInt   lact = 0;

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < st->contacts->n; k++) {
    const KergsContact *c = &st->contacts->c[k];
    const PetscReal    *xa = &sc->x[KERGS_DIM * c->a];
    PetscReal           g;
    if (!st->solver->active[k]) continue;
    if (c->kind == KERGS_CONTACT_DISK_DISK) {
      const PetscReal *xb = &sc->x[KERGS_DIM * c->b];
      PetscReal        d2 = 0;
      for (PetscInt d = 0; d < KERGS_DIM; d++) d2 += (xa[d] - xb[d]) * (xa[d] - xb[d]);
      g = PetscSqrtReal(d2) - c->ra - c->rb;
    } else {
      const KergsWall *w = &sc->walls[c->b];
      g                  = -c->ra;
      for (PetscInt d = 0; d < KERGS_DIM; d++) g += (xa[d] - w->a[d]) * c->n[d];
    }
    lact++;
    loc[0] += PetscMax(0.0, -g);
    lmax = PetscMax(lmax, -g);
  }
  loc[1] = (PetscReal)lact;
  PetscCall(MPIU_Allreduce(loc, glob, 2, MPIU_REAL, MPI_SUM, st->comm));
  PetscCall(MPIU_Allreduce(&lmax, &gmax, 1, MPIU_REAL, MPI_MAX, st->comm));
  *mean    = glob[1] > 0 ? glob[0] / glob[1] : 0.0;
  *max     = gmax;
  *nactive = (PetscInt)glob[1];
  PetscFunctionReturn(0);
}

static PetscErrorCode SaveVelocities(KergsScene sc, PetscReal **vold, PetscReal **wold, PetscReal **wvold)
{
  PetscFunctionBeginUser;
  PetscCall(PetscMalloc3(KERGS_DIM * sc->nowned, vold, KERGS_NROT * sc->nowned, wold, KERGS_DIM * sc->nwalls, wvold));
  PetscCall(PetscArraycpy(*vold, sc->v, KERGS_DIM * sc->nowned));
  PetscCall(PetscArraycpy(*wold, sc->omega, KERGS_NROT * sc->nowned));
  for (PetscInt w = 0; w < sc->nwalls; w++)
    for (PetscInt d = 0; d < KERGS_DIM; d++) (*wvold)[KERGS_DIM * w + d] = sc->walls[w].v[d];
  PetscFunctionReturn(0);
}

static PetscErrorCode RecordStep(KergsStepper st, const KergsSolveStats *ss, PetscLogDouble tdetect, PetscLogDouble tassemble)
{
  KergsResults res = st->results;
  PetscReal    mean = 0, max = 0, times[4] = {tdetect, tassemble, st->io_seconds, 0}, tmax[4], peak, sent;
  PetscInt     nactive = 0;
  PetscLogDouble now;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&now));
  times[3] = now - st->step_start;
  /* point-to-point and personalised collective bytes (PETSc's MPI logging; reductions are counted, not sized) */
  sent = (PetscReal)(petsc_send_len + petsc_isend_len - st->sent_start);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sent, 1, MPIU_REAL, MPIU_SUM, st->comm));
  PetscCall(MeasureViolation(st, &mean, &max, &nactive));
  PetscCall(MPIU_Allreduce(times, tmax, 4, MPIU_REAL, MPI_MAX, st->comm));
  PetscCall(PeakMemory(st->comm, &peak));
  st->max_violation = PetscMax(st->max_violation, max);
  if (!ss->converged) st->nonconverged++;
  PetscCall(KergsResultsRecord(res, "step", (PetscReal)st->scene->step));
  PetscCall(KergsResultsRecord(res, "time", st->scene->time));
  PetscCall(KergsResultsRecord(res, "contacts", (PetscReal)st->contacts->nglobal));
  PetscCall(KergsResultsRecord(res, "active", (PetscReal)nactive));
  PetscCall(KergsResultsRecord(res, "iterations", (PetscReal)ss->iterations));
  PetscCall(KergsResultsRecord(res, "converged", ss->converged ? 1.0 : 0.0));
  PetscCall(KergsResultsRecord(res, "residual", ss->residual));
  PetscCall(KergsResultsRecord(res, "criterion", ss->criterion));
  PetscCall(KergsResultsRecord(res, "mean_violation", mean));
  PetscCall(KergsResultsRecord(res, "max_violation", max));
  PetscCall(KergsResultsRecord(res, "solve_seconds", ss->seconds));
  PetscCall(KergsResultsRecord(res, "detect_seconds", tmax[0]));
  PetscCall(KergsResultsRecord(res, "assemble_seconds", tmax[1]));
  PetscCall(KergsResultsRecord(res, "sweep_seconds", ss->sweep_seconds));
  PetscCall(KergsResultsRecord(res, "io_seconds", tmax[2]));
  PetscCall(KergsResultsRecord(res, "step_seconds", tmax[3]));
  PetscCall(KergsResultsRecord(res, "sent_bytes", sent));
  PetscCall(KergsResultsRecord(res, "peak_memory", peak));
  PetscCall(KergsResultsRecord(res, "baseline_memory", st->baseline_rss));
  PetscCall(KergsSolverRecordStats(st->solver, st->ops, res));
  PetscCall(KergsPartitionRecord(st->partition, st->scene, st->contacts, ss->sweep_seconds, ss->compute_seconds, res));
  PetscCall(KergsResultsEndStep(res));
  if (!st->quiet)
    PetscCall(PetscPrintf(st->comm, "step %5" PetscInt_FMT " t %-10.5g contacts %6" PetscInt_FMT " active %6" PetscInt_FMT " sweeps %4" PetscInt_FMT "%s residual %8.2e violation mean %8.2e max %8.2e solve %.3g s\n", st->scene->step, (double)st->scene->time,
                          st->contacts->nglobal, nactive, ss->iterations, ss->converged ? "  " : " !", (double)ss->residual, (double)mean, (double)max, (double)ss->seconds));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperStep(KergsStepper st)
{
  KergsScene      sc = st->scene;
  KergsSolveStats ss;
  PetscLogDouble  t0, t1, t2;
  PetscReal      *vold, *wold, *wvold;
  PetscBool       due, keepH;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&st->step_start));
  st->sent_start = petsc_send_len + petsc_isend_len;
  /* initial partition before the first detection, then checks every -partition_check_every steps, with the
     contacts of the previous step (after its solve): migrates the disks and their contacts when due */
  PetscCall(KergsPartitionUpdate(st->partition, sc, st->contacts, NULL));
  PetscCall(PetscTime(&t0));
  PetscCall(KergsContactsDetect(st->contacts, sc));
  if (sc->step == 0) PetscCall(CheckInitialOverlaps(st));
  PetscCall(PetscTime(&t1));
  /* v^d, then W: unless kept, H is freed before W exists, built again for the update once W is freed, and freed after
     it. W couples the active contacts only, unless the solver works on the whole W (the kernel-regularised types). */
  keepH = (PetscBool)(st->keep_H || st->solver->needs_H);
  PetscCall(KergsOperatorsAssembleH(st->ops, sc, st->contacts, keepH));
  PetscCall(KergsOperatorsAssembleW(st->ops, sc, st->contacts, (PetscBool)!st->solver->needs_H));
  PetscCall(KergsOperatorsGetImpulses(st->ops, st->contacts)); /* warm start */
  PetscCall(PetscTime(&t2));
  PetscCall(KergsSolverSolve(st->solver, sc, st->contacts, st->ops, &ss));
  PetscCall(KergsOperatorsSetImpulses(st->ops, st->contacts));
  if (sc->step == st->fclib_step) PetscCall(KergsFCLibExport(sc, st->contacts, st->ops, st->solver->active, st->fclib_path));
  PetscCall(PetscLogEventBegin(KERGS_Update, 0, 0, 0, 0));
  if (!keepH) {
    PetscCall(KergsOperatorsReleaseW(st->ops));
    PetscCall(KergsOperatorsBuildHf(st->ops, sc, st->contacts));
  }
  PetscCall(SaveVelocities(sc, &vold, &wold, &wvold));
  PetscCall(KergsOperatorsUpdateVelocities(st->ops, sc));
  if (!keepH) PetscCall(KergsOperatorsReleaseH(st->ops));
  PetscCall(UpdatePositions(sc, vold, wold, wvold));
  PetscCall(PetscFree3(vold, wold, wvold));
  /* the ghosts' new state, for the measures and the next detection (which rebuilds the layer after a migration or
     once a disk moved half the skin) */
  PetscCall(KergsSceneRefreshGhosts(sc));
  sc->time += sc->dt;
  sc->step++;
  PetscCall(PetscLogEventEnd(KERGS_Update, 0, 0, 0, 0));
  st->io_seconds = 0;
  PetscCall(KergsResultsSnapshotDue(st->results, sc->step, PETSC_FALSE, &due)); /* the last one is KergsStepperRun's */
  if (due) {
    PetscLogDouble t3, t4;
    PetscCall(PetscTime(&t3));
    PetscCall(KergsResultsSnapshot(st->results, sc, st->contacts));
    PetscCall(PetscTime(&t4));
    st->io_seconds = t4 - t3;
  }
  PetscCall(RecordStep(st, &ss, t1 - t0, t2 - t1));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperRun(KergsStepper st)
{
  KergsScene sc = st->scene;
  PetscReal  ek, vmax;
  PetscBool  rest = PETSC_FALSE, moved = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(KergsResultsOpen(st->results));
  PetscCall(KergsResultsSnapshot(st->results, sc, st->contacts));
  while (sc->step < sc->nsteps && !rest) {
    PetscCall(KergsStepperStep(st));
    if (st->rest_speed > 0) {
      /* at rest: every grain slower than the threshold, once the packing has been set in motion */
      PetscCall(KergsSceneKineticEnergy(sc, &ek, &vmax));
      if (vmax >= st->rest_speed) moved = PETSC_TRUE;
      rest = (PetscBool)(moved && vmax < st->rest_speed);
    }
  }
  PetscCall(KergsResultsSnapshot(st->results, sc, st->contacts));
  PetscCall(KergsResultsClose(st->results));
  if (st->sample_out[0]) PetscCall(KergsSampleWrite(sc, st->sample_out));
  PetscCall(KergsSceneKineticEnergy(sc, &ek, &vmax));
  PetscCall(PetscPrintf(st->comm, "kergs: %" PetscInt_FMT " steps%s, %" PetscInt_FMT " not converged (cap %" PetscInt_FMT " sweeps), largest interpenetration %.3g, kinetic energy %.3g, fastest grain %.3g\n", sc->step, rest ? " (at rest)" : "", st->nonconverged, st->solver->max_it,
                        (double)st->max_violation, (double)ek, (double)vmax));
  if (st->partition->view) PetscCall(KergsPartitionView(st->partition, PETSC_VIEWER_STDOUT_(st->comm)));
  if (st->results->enabled) PetscCall(PetscPrintf(st->comm, "kergs: results in %s\n", st->results->path));
  if (st->sample_out[0]) PetscCall(PetscPrintf(st->comm, "kergs: sample in %s\n", st->sample_out));
  if (st->fclib_step >= 0 && st->fclib_step < sc->step) PetscCall(PetscPrintf(st->comm, "kergs: FCLib problem of step %" PetscInt_FMT " in %s\n", st->fclib_step, st->fclib_path));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperDestroy(KergsStepper *st)
{
  PetscFunctionBeginUser;
  if (!*st) PetscFunctionReturn(0);
  PetscCall(KergsPartitionDestroy(&(*st)->partition));
  PetscCall(KergsResultsDestroy(&(*st)->results));
  PetscCall(KergsSolverDestroy(&(*st)->solver));
  PetscCall(KergsOperatorsDestroy(&(*st)->ops));
  PetscCall(KergsContactsDestroy(&(*st)->contacts));
  PetscCall(KergsSceneDestroy(&(*st)->scene));
  PetscCall(PetscFree(*st));
  PetscFunctionReturn(0);
}
