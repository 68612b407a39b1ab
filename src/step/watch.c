/* kergs stepper: the run's watch (docs/running.md, "Blow-ups and solver failures"). Before the first step: no grain
   outside the container. After every step: no grain left the container, no interpenetration beyond -blowup_overlap of
   the smaller radius, no kinetic energy that the work of gravity, of the driven walls and of the free walls' forces
   cannot explain (-blowup_energy), and no solver whose natural residual stays above -solver_divergence_tol. Every
   figure it decides on is reduced over the ranks first, so that every rank stops after the same step. */
#include <kergs/private/stepperimpl.h>

PetscErrorCode KergsStepperWatchOptions(KergsStepper st)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(st->comm, NULL, "Blow-up and solver failure detection (docs/running.md)", NULL);
  PetscCall(PetscOptionsReal(
      "-blowup_overlap", "Stop with status 2 once an interpenetration exceeds this fraction of the smaller radius of the pair (0: never)",
      "", st->blowup_overlap, &st->blowup_overlap, NULL));
  PetscCall(PetscOptionsReal("-blowup_energy",
                             "Stop with status 2 once a step's kinetic energy exceeds this multiple of what the energy at its start and "
                             "the work of gravity and walls explain (0: never)",
                             "", st->blowup_energy, &st->blowup_energy, NULL));
  PetscCall(PetscOptionsReal("-solver_divergence_tol",
                             "A step whose natural residual exceeds this has diverged (0: never); -solver_divergence_steps in a row stop "
                             "the run with status 5",
                             "", st->divergence_tol, &st->divergence_tol, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-solver_divergence_steps", "Diverged steps in a row that stop the run with status 5", "",
                            st->divergence_steps, &st->divergence_steps, NULL));
  {
    static const char *const actions[] = {"stop", "continue"};
    PetscInt                 action    = st->on_infeasible_continue ? 1 : 0;
    PetscCall(PetscOptionsEList("-on_infeasible",
                                "A step the solver proves has no solution (DIVERGED_INFEASIBLE): stop (status 5, results kept to the "
                                "previous step) or continue (its answer applied, the step recorded as not converged)",
                                "", actions, 2, actions[action], &action, NULL));
    st->on_infeasible_continue = (PetscBool)(action == 1);
  }
  PetscOptionsEnd();
  PetscCheck(st->blowup_overlap >= 0 && !PetscIsInfOrNanReal(st->blowup_overlap), st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-blowup_overlap %g must be a non-negative fraction of a radius (0: never)", (double)st->blowup_overlap);
  PetscCheck(st->blowup_energy == 0 || (st->blowup_energy >= 1 && !PetscIsInfOrNanReal(st->blowup_energy)), st->comm,
             PETSC_ERR_ARG_OUTOFRANGE, "-blowup_energy %g must be at least 1 (or 0: never)", (double)st->blowup_energy);
  PetscCheck(st->divergence_tol >= 0 && !PetscIsInfOrNanReal(st->divergence_tol), st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_divergence_tol %g must be non-negative (0: never)", (double)st->divergence_tol);
  PetscCheck(st->divergence_steps >= 1, st->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_divergence_steps %" PetscInt_FMT " must be at least 1",
             st->divergence_steps);
  PetscFunctionReturn(0);
}

/* A wall's unit inward normal (the left normal of a -> b) */
static void WatchWallNormal(const KergsWall *w, PetscReal n[])
{
  const PetscReal dx = w->b[0] - w->a[0], dy = w->b[1] - w->a[1], len = PetscSqrtReal(dx * dx + dy * dy);

  n[0] = len > 0 ? -dy / len : 0.0;
  n[1] = len > 0 ? dx / len : 0.0;
}

/* The wall whose back side holds the centre x within the wall's extent (a segment's span, a line anywhere), or -1.
   Spans, not the walls' half-planes: grains leaving a hopper through its opening pass below the meeting point of its
   walls' lines without leaving the container. */
static PetscInt WatchBehindWall(PetscInt nwalls, const KergsWall walls[], const PetscReal x[])
{
  for (PetscInt w = 0; w < nwalls; w++) {
    PetscReal n[KERGS_DIM], s = 0, along = 0, len2 = 0;
    WatchWallNormal(&walls[w], n);
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      const PetscReal ab = walls[w].b[d] - walls[w].a[d];
      s += n[d] * (x[d] - walls[w].a[d]);
      along += ab * (x[d] - walls[w].a[d]);
      len2 += ab * ab;
    }
    if (s < 0 && (walls[w].infinite || (along >= 0 && along <= len2))) return w;
  }
  return -1;
}

/* The smallest grain id (over all ranks) whose centre is outside the container, and the wall it is behind; id -1:
   none. Collective. */
PetscErrorCode KergsStepperFindOutside(KergsStepper st, PetscInt *grain, PetscInt *wall)
{
  KergsDisks       D;
  const KergsWall *walls;
  PetscInt         nwalls, mine = PETSC_MAX_INT, mywall = -1, g, w;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  for (PetscInt i = 0; i < D.nowned; i++) {
    const PetscInt k = WatchBehindWall(nwalls, walls, &D.x[KERGS_DIM * i]);
    if (PetscIsInfOrNanReal(D.x[KERGS_DIM * i]) || PetscIsInfOrNanReal(D.x[KERGS_DIM * i + 1])) continue; /* the poll's to report */
    if (k >= 0 && D.id[i] < mine) {
      mine   = D.id[i];
      mywall = k;
    }
  }
  PetscCall(MPIU_Allreduce(&mine, &g, 1, MPIU_INT, MPI_MIN, st->comm));
  w = g == mine ? mywall : -1;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &w, 1, MPIU_INT, MPI_MAX, st->comm));
  *grain = g == PETSC_MAX_INT ? -1 : g;
  *wall  = w;
  PetscFunctionReturn(0);
}

/* Before the first step: every grain's centre inside the container (an error naming the first grain outside). */
PetscErrorCode KergsStepperCheckContainer(KergsStepper st)
{
  const KergsWall *walls;
  KergsDisks       D;
  PetscInt         grain, wall;

  PetscFunctionBeginUser;
  PetscCall(KergsStepperFindOutside(st, &grain, &wall));
  if (grain < 0) PetscFunctionReturn(0);
  PetscCall(KergsSceneGetWalls(st->scene, NULL, &walls));
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  for (PetscInt i = 0; i < D.nowned; i++)
    if (D.id[i] == grain)
      PetscCall(PetscPrintf(PETSC_COMM_SELF, "[kergs] grain %" PetscInt_FMT " at (%g, %g) is behind wall %s\n", grain,
                            (double)D.x[KERGS_DIM * i], (double)D.x[KERGS_DIM * i + 1], walls[wall].name));
  SETERRQ(st->comm, PETSC_ERR_USER_INPUT,
          "Grain %" PetscInt_FMT " starts outside the container: its centre is behind wall %s (position printed above); move it, or the "
          "wall",
          grain, walls[wall].name);
}

/* Kinetic energy of the disks and of the free walls, and the fastest disk's speed. Collective. */
PetscErrorCode KergsStepperEnergy(KergsStepper st, PetscReal *ek, PetscReal *vmax)
{
  const KergsWall *walls;
  PetscInt         nwalls;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneKineticEnergy(st->scene, ek, vmax));
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  for (PetscInt w = 0; w < nwalls; w++)
    if (walls[w].kind == KERGS_WALL_FREE) *ek += 0.5 * walls[w].mass * (PetscSqr(walls[w].v[0]) + PetscSqr(walls[w].v[1]));
  PetscFunctionReturn(0);
}

/* The work done on the bodies during the step, after the velocity update (V+ in place, V- given): gravity on the
   disks, dt g.(theta v+ + (1 - theta) v-) m; the driven walls' impulses times their velocities; the free walls'
   applied forces times their displacements. Collective. */
PetscErrorCode KergsStepperExternalWork(KergsStepper st, const PetscReal vold[], const PetscReal wvold[], PetscReal *work,
                                        PetscReal *driven_work)
{
  KergsDisks       D;
  const KergsWall *walls;
  KergsContact    *c;
  PetscReal        g[KERGS_DIM], dt, theta, wk[2] = {0, 0}, sums[2]; /* all, driven walls */
  PetscInt         nwalls, n;
  PetscBool        frictional;
  PetscMPIInt      rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(st->comm, &rank));
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  PetscCall(KergsSceneGetGravity(st->scene, g));
  PetscCall(KergsSceneGetTimeStep(st->scene, &dt, &theta));
  PetscCall(KergsSceneGetModel(st->scene, &frictional, NULL));
  PetscCall(KergsContactsGetLocal(st->contacts, &n, &c));
  for (PetscInt i = 0; i < D.nowned; i++)
    for (PetscInt d = 0; d < KERGS_DIM; d++)
      wk[0] += dt * D.mass[i] * g[d] * (theta * D.v[KERGS_DIM * i + d] + (1 - theta) * vold[KERGS_DIM * i + d]);
  for (PetscInt k = 0; k < n; k++) {
    const KergsWall *w;
    if (c[k].kind != KERGS_CONTACT_DISK_WALL) continue;
    w = &walls[c[k].b];
    if (w->kind != KERGS_WALL_DRIVEN) continue;
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      const PetscReal term = (c[k].r[0] * c[k].n[d] + (frictional ? c[k].r[1] * c[k].t[d] : 0.0)) * w->v[d];
      wk[0] += term; /* in the order of the sum before the driven part was kept apart: the same bits */
      wk[1] += term;
    }
  }
  if (rank == 0) /* the walls are replicated: counted once */
    for (PetscInt w = 0; w < nwalls; w++)
      if (walls[w].kind == KERGS_WALL_FREE)
        for (PetscInt d = 0; d < KERGS_DIM; d++)
          wk[0] += dt * walls[w].force[d] * (theta * walls[w].v[d] + (1 - theta) * wvold[KERGS_DIM * w + d]);
  PetscCall(MPIU_Allreduce(wk, sums, 2, MPIU_REAL, MPIU_SUM, st->comm));
  *work        = sums[0];
  *driven_work = sums[1];
  PetscFunctionReturn(0);
}

/* Once per run: two grains approaching at twice the fastest speed close more than the alert distance in a step, so a
   contact may be met before detection sees it (the rules then act on a late, deep contact). A warning, not a failure.
   The automatic alert follows the speed at each step's start (KergsSceneAdaptAlert): it is outrun only when a step
   more than doubled the fastest speed (an impact). */
static PetscErrorCode WatchAlert(KergsStepper st, PetscInt step)
{
  PetscReal dt, alert;
  PetscBool automatic;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetTimeStep(st->scene, &dt, NULL));
  PetscCall(KergsSceneGetContactRule(st->scene, &alert, NULL));
  PetscCall(KergsSceneGetAlertFloor(st->scene, &automatic, NULL));
  if (st->warned_alert || !(2 * st->vmax_end * dt > alert)) PetscFunctionReturn(0);
  st->warned_alert = PETSC_TRUE;
  PetscCall(PetscPrintf(
      st->comm,
      "kergs: warning: after step %" PetscInt_FMT " grains move up to %.3g a step (fastest %.3g m/s), and two of them may "
      "close by twice that, more than the alert distance %.3g: contacts may be met before they are detected (%s)\n",
      step, (double)(st->vmax_end * dt), (double)st->vmax_end, (double)alert,
      automatic ? "the automatic alert follows from the next step; lower -dt if impacts outrun it" : "raise -alert or lower -dt"));
  PetscFunctionReturn(0);
}

/* After a step's statistics: decide whether the run blew up or its solver diverged; st->failure says what (empty:
   neither) and st->failure_status the exit status. The same on every rank: every figure is global. */
static PetscErrorCode WatchStep(KergsStepper st, const KergsSolveStats *ss)
{
  const PetscReal  residual = ss->residual;
  const KergsWall *walls;
  PetscInt         step, grain, wall;
  PetscReal        explained;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetStep(st->scene, &step, NULL, NULL));
  PetscCall(KergsSceneGetWalls(st->scene, NULL, &walls));
  st->failure[0] = 0;
  if (PetscIsInfOrNanReal(st->ek_end)) {
    /* positions or velocities not finite: the poll names the grain; finite but too large for their energy to be
       (-gravity 0,-1e300: velocities of 1e297 m/s) is a blow-up named here, before the next step's detection and
       ghost layer work on such positions */
    PetscInt bad = KergsStepperFirstNonFiniteGrain(st->scene);
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT, MPI_MIN, st->comm));
    if (bad == PETSC_MAX_INT) {
      PetscCall(PetscSNPrintf(st->failure, sizeof(st->failure),
                              "blow-up in step %" PetscInt_FMT ": the kinetic energy overflows (velocities beyond 1e150 m/s)", step));
      st->failure_status = KERGS_EXIT_BLOWUP;
      st->failure_kind   = "kinetic energy";
    }
    PetscFunctionReturn(0);
  }
  PetscCall(KergsStepperFindOutside(st, &grain, &wall));
  if (grain >= 0) {
    PetscCall(PetscSNPrintf(st->failure, sizeof(st->failure),
                            "blow-up in step %" PetscInt_FMT ": grain %" PetscInt_FMT " left the container (its centre is behind wall %s)",
                            step, grain, walls[wall].name));
    st->failure_status = KERGS_EXIT_BLOWUP;
    st->failure_kind   = "grain out of the container";
    PetscFunctionReturn(0);
  }
  if (st->blowup_overlap > 0 && st->last_max_relative > st->blowup_overlap) {
    PetscCall(PetscSNPrintf(st->failure, sizeof(st->failure),
                            "blow-up in step %" PetscInt_FMT
                            ": an interpenetration of %.3g reaches %.3g times the smaller radius of its pair "
                            "(-blowup_overlap %g)",
                            step, (double)st->last_max_violation, (double)st->last_max_relative, (double)st->blowup_overlap));
    st->failure_status = KERGS_EXIT_BLOWUP;
    st->failure_kind   = "interpenetration";
    PetscFunctionReturn(0);
  }
  /* the energy at the start plus the work done: what the kinetic energy at the end can be, if no contact created
     energy (contacts of the law dissipate or keep it); the floor, the scene's own energy scale, keeps rounding at rest
     from counting */
  /* a driven wall's work is that of the contact impulses on it: on a step proved infeasible (applied under
     -on_infeasible continue) they are the solver's runaway impulses, and would explain anything. Other steps that did
     not converge keep it: capped NLGS's bounded impulses on confine500 push the grains as the wall does, and without
     the wall's work its first step would count as a blow-up (measured) */
  explained = st->ek_start + PetscAbsReal(ss->reason == KERGS_SOLVER_DIVERGED_INFEASIBLE ? st->work - st->driven_work : st->work) +
              st->energy_floor;
  if (st->blowup_energy > 0 && st->ek_end > st->blowup_energy * explained) {
    PetscCall(PetscSNPrintf(st->failure, sizeof(st->failure),
                            "blow-up in step %" PetscInt_FMT
                            ": the kinetic energy went from %.3g to %.3g, with %.3g of work done by gravity "
                            "and walls (-blowup_energy %g)",
                            step, (double)st->ek_start, (double)st->ek_end, (double)st->work, (double)st->blowup_energy));
    st->failure_status = KERGS_EXIT_BLOWUP;
    st->failure_kind   = "kinetic energy";
    PetscFunctionReturn(0);
  }
  PetscCall(WatchAlert(st, step));
  if (ss->reason == KERGS_SOLVER_DIVERGED_KERNEL) { /* decided from global figures by the type: the same on every rank */
    PetscCall(PetscSNPrintf(st->failure, sizeof(st->failure), "the contact solver failed in step %" PetscInt_FMT ": %s, %s", step,
                            KergsSolverConvergedReasons[ss->reason], KergsSolverConvergedReasonDescription(ss->reason)));
    st->failure_status = KERGS_EXIT_SOLVER_FAILED;
    st->failure_kind   = "contact solver failed";
    PetscFunctionReturn(0);
  }
  st->diverged_steps = st->divergence_tol > 0 && !(residual <= st->divergence_tol) ? st->diverged_steps + 1 : 0;
  if (st->diverged_steps >= st->divergence_steps) {
    PetscCall(PetscSNPrintf(st->failure, sizeof(st->failure),
                            "the contact solver diverged: natural residual above -solver_divergence_tol %g in %" PetscInt_FMT
                            " steps in a row, up to step %" PetscInt_FMT " (last %.3g)",
                            (double)st->divergence_tol, st->diverged_steps, step, (double)residual));
    st->failure_status = KERGS_EXIT_SOLVER_FAILED;
    st->failure_kind   = "contact solver diverged";
  }
  PetscFunctionReturn(0);
}

/* The scene's energy scale: lifting every grain by its radius against gravity, plus every grain moving at the
   fastest wall program's speed. Collective. */
PetscErrorCode KergsStepperEnergyFloor(KergsStepper st)
{
  KergsDisks       D;
  const KergsWall *walls;
  PetscInt         nwalls;
  PetscReal        g[KERGS_DIM], gn, vw = 0, e = 0;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  PetscCall(KergsSceneGetGravity(st->scene, g));
  gn = PetscSqrtReal(g[0] * g[0] + g[1] * g[1]);
  for (PetscInt w = 0; w < nwalls; w++)
    for (PetscInt k = 0; k < walls[w].nprog; k++)
      vw = PetscMax(vw, PetscSqrtReal(PetscSqr(walls[w].prog_v[k][0]) + PetscSqr(walls[w].prog_v[k][1])));
  for (PetscInt i = 0; i < D.nowned; i++) e += D.mass[i] * (gn * D.radius[i] + 0.5 * vw * vw);
  PetscCall(MPIU_Allreduce(&e, &st->energy_floor, 1, MPIU_REAL, MPIU_SUM, st->comm));
  st->energy_floor *= 1e-6;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperWatch(KergsStepper st, const KergsSolveStats *ss)
{
  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(KERGS_Watch, 0, 0, 0, 0));
  PetscCall(WatchStep(st, ss));
  PetscCall(PetscLogEventEnd(KERGS_Watch, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* The grains (by id, sorted, without repeats) and walls of the contacts of weight at least 1 % in the certificate's
   network, over all ranks. ids (PetscFree) holds *nids grain ids; wall_in[w] says whether wall w takes part. */
static PetscErrorCode InfeasibleNetwork(KergsStepper st, const PetscReal weights[], PetscInt *nids, PetscInt **ids, PetscBool wall_in[])
{
  KergsDisks    D;
  KergsContact *c;
  PetscInt      n, nwalls, nlocal = 0, *local, *walls_in;
  PetscMPIInt   size, *counts, *displs, total;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, NULL));
  PetscCall(KergsContactsGetLocal(st->contacts, &n, &c));
  PetscCallMPI(MPI_Comm_size(st->comm, &size));
  PetscCall(PetscMalloc1(2 * n + 1, &local));
  PetscCall(PetscCalloc1(nwalls + 1, &walls_in));
  for (PetscInt k = 0; k < n; k++) {
    if (!(weights[k] >= 0.01)) continue;
    local[nlocal++] = D.id[c[k].a];
    if (c[k].kind == KERGS_CONTACT_DISK_DISK)
      local[nlocal++] = D.id[c[k].b];
    else
      walls_in[c[k].b] = 1;
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, walls_in, nwalls, MPIU_INT, MPI_MAX, st->comm));
  for (PetscInt w = 0; w < nwalls; w++) wall_in[w] = (PetscBool)(walls_in[w] > 0);
  PetscCall(PetscSortRemoveDupsInt(&nlocal, local));
  PetscCall(PetscMalloc2(size, &counts, size + 1, &displs));
  {
    PetscMPIInt mine = (PetscMPIInt)nlocal;
    PetscCallMPI(MPI_Allgather(&mine, 1, MPI_INT, counts, 1, MPI_INT, st->comm));
  }
  displs[0] = 0;
  for (PetscMPIInt q = 0; q < size; q++) displs[q + 1] = displs[q] + counts[q];
  total = displs[size];
  PetscCall(PetscMalloc1(total + 1, ids));
  PetscCallMPI(MPI_Allgatherv(local, (PetscMPIInt)nlocal, MPIU_INT, *ids, counts, displs, MPIU_INT, st->comm));
  *nids = total;
  PetscCall(PetscSortRemoveDupsInt(nids, *ids));
  PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree(local));
  PetscCall(PetscFree(walls_in));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperReportInfeasible(KergsStepper st, PetscInt step)
{
  const PetscReal *weights;
  const KergsWall *walls;
  PetscInt         nwalls, nids, *ids;
  PetscBool       *wall_in;
  char             grains[160] = "", names[160] = "";
  size_t           len;

  PetscFunctionBeginUser;
  PetscCall(KergsSolverGetInfeasibleNetwork(st->solver, &weights));
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  PetscCall(PetscCalloc1(nwalls + 1, &wall_in));
  PetscCall(InfeasibleNetwork(st, weights, &nids, &ids, wall_in));
  /* the grains as ranges of consecutive ids, as many as fit */
  for (PetscInt i = 0; i < nids;) {
    PetscInt j = i;
    while (j + 1 < nids && ids[j + 1] == ids[j] + 1) j++;
    PetscCall(PetscStrlen(grains, &len));
    if (len + 40 >= sizeof(grains)) {
      PetscCall(PetscStrlcat(grains, ", ...", sizeof(grains)));
      break;
    }
    if (j > i)
      PetscCall(PetscSNPrintf(grains + len, sizeof(grains) - len, "%s%" PetscInt_FMT "-%" PetscInt_FMT, i ? ", " : "", ids[i], ids[j]));
    else
      PetscCall(PetscSNPrintf(grains + len, sizeof(grains) - len, "%s%" PetscInt_FMT, i ? ", " : "", ids[i]));
    i = j + 1;
  }
  for (PetscInt w = 0; w < nwalls; w++) {
    if (!wall_in[w]) continue;
    PetscCall(PetscStrlen(names, &len));
    if (len + 40 >= sizeof(names)) break;
    PetscCall(PetscSNPrintf(names + len, sizeof(names) - len, "%s%s", len ? ", " : "", walls[w].name));
  }
  PetscCall(PetscSNPrintf(st->failure, sizeof(st->failure),
                          "step %" PetscInt_FMT " has no solution: the %" PetscInt_FMT
                          " grains %s%s%s hold a compressive self-equilibrated "
                          "network that the imposed velocities shorten (rigid grains cannot; -on_infeasible continue applies the "
                          "solver's answer anyway; results kept to step %" PetscInt_FMT ")",
                          step, nids, grains, names[0] ? " between walls " : "", names, step - 1));
  st->failure_status = KERGS_EXIT_SOLVER_FAILED;
  st->failure_kind   = "infeasible step";
  PetscCall(PetscFree(ids));
  PetscCall(PetscFree(wall_in));
  PetscFunctionReturn(0);
}
