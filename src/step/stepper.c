/* kergs stepper: the time loop of Algorithm 1 (Moreau-Jean, theta-method). Data flows one way per step:
   scene state -> detect -> operators -> solver -> update -> results. */
#include <kergs/private/stepperimpl.h>
#include <math.h>
#include <kergs/sample.h>
#include <kergs/fclib.h>

PetscErrorCode KergsStepperCreate(MPI_Comm comm, KergsStepper *stepper)
{
  KergsStepper st;

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscNew(&st));
  st->comm             = comm;
  st->fclib_step       = -1;
  st->checkpoint_step  = -1;
  st->overlap_tol      = 5e-2; /* a settled NSCD sample keeps interpenetrations of about 1% of a radius */
  st->blowup_overlap   = 0.5;  /* fifty times what a settled sample keeps */
  st->blowup_energy    = 2.0;
  st->divergence_tol   = 0.7; /* r = 0 scores 1 (KergsLawNaturalResidualScaled); a diverging NLGS-Jac 0.78-0.93 */
  st->divergence_steps = 5;
  st->sample_forces    = PETSC_TRUE;
  st->rest_window      = 50;   /* 0.05 s at cases/compact_small.opts's dt, 0.1 s at the large compactions' 2e-3 */
  st->rest_stress      = 0.05; /* stress_gap where the inertial rule stops: 0.16 % (120 grains), 2.7 % (20,000 disks) */
  st->box_inertial     = -1;
  PetscCall(KergsStepperPeakMemory(comm, &st->baseline_rss));
  PetscCall(KergsSceneCreate(comm, &st->scene));
  PetscCall(KergsContactsCreate(comm, &st->contacts));
  PetscCall(KergsOperatorsCreate(comm, &st->ops));
  PetscCall(KergsSolverCreate(comm, &st->solver));
  PetscCall(KergsResultsCreate(comm, &st->results));
  PetscCall(KergsPartitionCreate(comm, &st->partition));
  *stepper = st;
  PetscFunctionReturn(0);
}

/* -dt as written: a finite time step ("-dt inf" was told "must be positive"). -steps is checked where the scene reads it
   (KergsOptionsInt). */
static PetscErrorCode CheckClockOptions(MPI_Comm comm)
{
  char      value[256];
  PetscBool set;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-dt", value, sizeof(value), &set));
  if (set) {
    char        *end;
    const double dt = strtod(value, &end);
    PetscCheck(end == value || *end || isfinite(dt), comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Option -dt %s: the time step must be a finite positive number of seconds", value);
  }
  PetscFunctionReturn(0);
}

/* Options given where they would do nothing: refused, naming what they need. Not on a restart, which takes its options
   from the checkpoint and can change a value but not take an option away (-stop_at_rest_inertial 0 or -fclib_step -1
   must still work). */
static PetscErrorCode CheckOptionsDoingNothing(KergsStepper st, PetscBool rest_stress_set, PetscBool rest_window_set,
                                               PetscBool sample_forces_set, PetscBool fclib_output_set)
{
  char      source[16];
  PetscBool file;

  PetscFunctionBeginUser;
  if (st->restart_path[0]) PetscFunctionReturn(0);
  PetscCheck(!rest_stress_set || st->rest_inertial > 0, st->comm, PETSC_ERR_ARG_INCOMP,
             "-stop_at_rest_stress holds back the stop of -stop_at_rest_inertial, which is not given: give both, or neither");
  PetscCheck(!rest_window_set || st->rest_inertial > 0, st->comm, PETSC_ERR_ARG_INCOMP,
             "-stop_at_rest_window is the window of -stop_at_rest_inertial, which is not given: give both, or neither");
  PetscCall(KergsSceneDisksSourceFromOptions(source, sizeof(source)));
  PetscCall(PetscStrcmp(source, "file", &file));
  PetscCheck(!sample_forces_set || file, st->comm, PETSC_ERR_ARG_INCOMP,
             "-sample_forces takes the first step's impulses from the sample file of -disks_source file, and the disks come from "
             "-disks_source %s: drop it",
             source);
  PetscCheck(!fclib_output_set || st->fclib_step >= 1, st->comm, PETSC_ERR_ARG_INCOMP,
             "-fclib_output %s is the file of the step -fclib_step exports, and no step is given: add -fclib_step N", st->fclib_path);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperSetFromOptions(KergsStepper st)
{
  const char *name;
  PetscBool   help, rest_stress_set = PETSC_FALSE, rest_window_set = PETSC_FALSE, fclib_output_set = PETSC_FALSE,
                  sample_forces_set = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsHasHelp(NULL, &help));
  PetscCall(KergsStepperBatchOptions(st)); /* first: a restart changes how the scene reads its options */
  if (st->restart_path[0] && !help) PetscCall(KergsSceneSetRestoring(st->scene, PETSC_TRUE));
  PetscCall(CheckClockOptions(st->comm)); /* before the scene reads them: messages that name the option */
  PetscCall(KergsSceneSetFromOptions(st->scene));
  PetscCall(KergsSolverSetFromOptions(st->solver));
  PetscCall(KergsSceneGetName(st->scene, &name));
  PetscCall(KergsResultsSetSceneName(st->results, name)); /* default -output: results/<scene>.h5 */
  PetscCall(KergsResultsSetFromOptions(st->results));
  PetscCall(KergsPartitionSetFromOptions(st->partition));
  PetscCall(KergsStepperWatchOptions(st));
  PetscOptionsBegin(st->comm, NULL, "Time stepping options", NULL);
  PetscCall(PetscOptionsReal("-stop_at_rest",
                             "Stop once every disk is slower than this speed, after the packing has moved faster (0: not this way)", "",
                             st->rest_speed, &st->rest_speed, NULL));
  PetscCall(
      PetscOptionsReal("-stop_at_rest_energy",
                       "Or stop once the kinetic energy per grain (J/m) is below this, after the packing has had more (0: not this way; "
                       "when given, it alone says that the packing has moved)",
                       "", st->rest_energy, &st->rest_energy, NULL));
  PetscCall(PetscOptionsReal(
      "-stop_at_rest_inertial",
      "Or stop once the box's inertial number I = eps_dot d sqrt(rho / p) is below this, after it has been above (e.g. 1e-4, "
      "ten times below the quasi-static bound 1e-3): eps_dot the path the distance between a wall under pressure p and "
      "the wall facing it travels over -stop_at_rest_window steps, per second and per that distance (0: not this way)",
      "", st->rest_inertial, &st->rest_inertial, NULL));
  PetscCall(
      KergsOptionsInt(PetscOptionsObject, "-stop_at_rest_window",
                      "Steps over which -stop_at_rest_inertial measures the walls' motion (inertial_number is -1 until they have run)", "",
                      st->rest_window, &st->rest_window, &rest_window_set));
  PetscCall(PetscOptionsReal(
      "-stop_at_rest_stress",
      "With -stop_at_rest_inertial: stop only once the Love-Weber stress and the walls' tractions' (friction included), "
      "averaged over the same window, differ by at most this times p along each pressure wall's normal (stress_gap; 0: not checked)",
      "", st->rest_stress, &st->rest_stress, &rest_stress_set));
  PetscCall(PetscOptionsString("-sample_output", "Write the final packing to this sample file (HDF5), for -disks_source file", "",
                               st->sample_out, st->sample_out, sizeof(st->sample_out), NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-sample_forces",
                             "With -disks_source file: start the first step from the contact forces the sample records, as a restart "
                             "would (false: from zero impulses)",
                             "", st->sample_forces, &st->sample_forces, &sample_forces_set));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-fclib_step",
                            "Export in FCLib format the local problem solved in this step, numbered as the step lines (1: the first step; "
                            "-1: none)",
                            "", st->fclib_step, &st->fclib_step, NULL));
  PetscCall(PetscOptionsString("-fclib_output",
                               "FCLib file of -fclib_step (with -fclib_input: the problem solved, with the solution found)", "",
                               st->fclib_path, st->fclib_path, sizeof(st->fclib_path), &fclib_output_set));
  PetscCall(PetscOptionsReal("-initial_overlap_tol", "Largest initial interpenetration allowed, relative to the smaller radius of the pair",
                             "", st->overlap_tol, &st->overlap_tol, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-quiet", "Do not print a summary line per step", "", st->quiet, &st->quiet, NULL));
  PetscCall(KergsOptionsBool(
      PetscOptionsObject, "-keep_H",
      "Keep H_f and H_g through the solve, next to W (default: freed before W is assembled and H_f assembled again for the velocity "
      "update, so that the peak memory is the larger of H and W, not their sum; solvers that use H keep it anyway)",
      "", st->keep_H, &st->keep_H, NULL));
  PetscOptionsEnd();
  PetscCheck(st->rest_speed >= 0 && !PetscIsInfOrNanReal(st->rest_speed), st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-stop_at_rest %g must be a non-negative speed", (double)st->rest_speed);
  PetscCheck(st->rest_energy >= 0 && !PetscIsInfOrNanReal(st->rest_energy), st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-stop_at_rest_energy %g must be a non-negative energy per grain", (double)st->rest_energy);
  PetscCheck(st->rest_inertial >= 0 && !PetscIsInfOrNanReal(st->rest_inertial), st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-stop_at_rest_inertial %g must be a non-negative inertial number", (double)st->rest_inertial);
  PetscCheck(st->rest_stress >= 0 && !PetscIsInfOrNanReal(st->rest_stress), st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-stop_at_rest_stress %g must be a non-negative fraction of the walls' pressure", (double)st->rest_stress);
  PetscCheck(st->rest_window >= 1, st->comm, PETSC_ERR_ARG_OUTOFRANGE, "-stop_at_rest_window %" PetscInt_FMT " must be at least 1 step",
             st->rest_window);
  PetscCheck(st->fclib_step == -1 || st->fclib_step >= 1, st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-fclib_step %" PetscInt_FMT " must be a step number (1 is the first step, as in the step lines) or -1 for none",
             st->fclib_step);
  PetscCheck(st->overlap_tol >= 0, st->comm, PETSC_ERR_ARG_OUTOFRANGE, "-initial_overlap_tol %g must be non-negative",
             (double)st->overlap_tol);
  PetscCall(CheckOptionsDoingNothing(st, rest_stress_set, rest_window_set, sample_forces_set, fclib_output_set));
  if (st->fclib_step >= 0 && !st->fclib_path[0])
    PetscCall(PetscSNPrintf(st->fclib_path, sizeof(st->fclib_path), "results/%s-step%" PetscInt_FMT ".fclib.h5", name[0] ? name : "kergs",
                            st->fclib_step));
  PetscCall(KergsStepperDefaultCheckpointPath(st));
  if (help) PetscFunctionReturn(0);
  PetscCall(KergsProvenanceSetOptions(st->comm)); /* the options as given, before any object adds its own */
  PetscCall(KergsStepperCheckPaths(st));          /* before the run writes anything */
  if (st->sample_forces && !st->restart_path[0]) PetscCall(KergsSampleReadForces(st->scene, NULL, NULL)); /* and the sample's forces */
  if (st->restart_path[0]) PetscCall(KergsStepperRestore(st));
  PetscCall(KergsStepperCheckRestInertial(st)); /* the steps left: a restart's */
  PetscFunctionReturn(0);
}

/* What runs, in one line (scene, size, steps, ranks, solver), then the views asked for on the command line
   (-scene_view, -solver_view, in PETSc's viewer syntax), as PETSc prints -ksp_view on request only. */
PetscErrorCode KergsStepperViewFromOptions(KergsStepper st)
{
  const char     *name;
  KergsSolverType type;
  KergsDisks      D;
  PetscInt        nwalls, nsteps, max_it;
  PetscReal       dt, theta, tol;
  PetscMPIInt     size;
  const char     *counted;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetName(st->scene, &name));
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, NULL));
  PetscCall(KergsSceneGetStep(st->scene, NULL, NULL, &nsteps));
  PetscCall(KergsSceneGetTimeStep(st->scene, &dt, &theta));
  PetscCall(KergsSolverGetType(st->solver, &type));
  PetscCall(KergsSolverGetTolerances(st->solver, &tol, &max_it));
  PetscCall(KergsSolverGetIterationName(st->solver, &counted));
  PetscCallMPI(MPI_Comm_size(st->comm, &size));
  PetscCall(PetscPrintf(st->comm,
                        "kergs: scene %s, %" PetscInt_FMT " disks, %" PetscInt_FMT " walls, %" PetscInt_FMT
                        " steps of %g s on %d rank%s; solver %s "
                        "to %g in at most %" PetscInt_FMT " %s (-scene_view, -solver_view for details)\n",
                        name[0] ? name : "unnamed", D.ndisks, nwalls, nsteps, (double)dt, (int)size, size > 1 ? "s" : "", type, (double)tol,
                        max_it, counted));
  PetscCall(KergsSceneViewFromOptions(st->scene, "-scene_view"));
  PetscCall(KergsSolverViewFromOptions(st->solver, "-solver_view"));
  PetscFunctionReturn(0);
}

/* Initial grains must not overlap (beyond a tolerance): report the first offending pair by grain id. */
static PetscErrorCode CheckInitialOverlaps(KergsStepper st)
{
  KergsDisks       D;
  const KergsWall *walls;
  KergsContact    *c;
  PetscInt         n, bad = -1, nbad;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  PetscCall(KergsSceneGetWalls(st->scene, NULL, &walls));
  PetscCall(KergsContactsGetLocal(st->contacts, &n, &c));
  for (PetscInt k = 0; k < n && bad < 0; k++) {
    PetscReal rmin = c[k].kind == KERGS_CONTACT_DISK_DISK ? PetscMin(c[k].ra, c[k].rb) : c[k].ra;
    if (c[k].gap < -st->overlap_tol * rmin) bad = k;
  }
  PetscCall(MPIU_Allreduce(bad >= 0 ? &(PetscInt){1} : &(PetscInt){0}, &nbad, 1, MPIU_INT, MPI_SUM, st->comm));
  if (bad >= 0) {
    const KergsContact *b = &c[bad];
    if (b->kind == KERGS_CONTACT_DISK_DISK)
      PetscCall(PetscPrintf(PETSC_COMM_SELF, "[kergs] grains %" PetscInt_FMT " and %" PetscInt_FMT " overlap by %g (radii %g, %g)\n",
                            D.id[b->a], D.id[b->b], (double)-b->gap, (double)b->ra, (double)b->rb));
    else
      PetscCall(PetscPrintf(PETSC_COMM_SELF, "[kergs] grain %" PetscInt_FMT " crosses wall %s by %g (radius %g)\n", D.id[b->a],
                            walls[b->b].name, (double)-b->gap, (double)b->ra));
  }
  if (nbad) PetscCall(KergsResultsDiscard(st->results)); /* opened already: no results of a run that did not start */
  PetscCheck(nbad == 0, st->comm, PETSC_ERR_USER_INPUT,
             "The initial packing has overlapping grains, or a grain crossing a wall (printed above); move them, or the wall (-box), or "
             "raise -initial_overlap_tol to accept interpenetrations up to that fraction of the smaller radius");
  PetscFunctionReturn(0);
}

/* V^- of the owned disks and of the walls, before the velocity update (x+ needs it for theta < 1). */
static PetscErrorCode SaveVelocities(KergsScene sc, PetscReal **vold, PetscReal **wold, PetscReal **wvold)
{
  KergsDisks       D;
  const KergsWall *walls;
  PetscInt         nwalls;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetWalls(sc, &nwalls, &walls));
  PetscCall(PetscMalloc3(KERGS_DIM * D.nowned, vold, KERGS_NROT * D.nowned, wold, KERGS_DIM * nwalls, wvold));
  PetscCall(PetscArraycpy(*vold, D.v, KERGS_DIM * D.nowned));
  PetscCall(PetscArraycpy(*wold, D.omega, KERGS_NROT * D.nowned));
  for (PetscInt w = 0; w < nwalls; w++)
    for (PetscInt d = 0; d < KERGS_DIM; d++) (*wvold)[KERGS_DIM * w + d] = walls[w].v[d];
  PetscFunctionReturn(0);
}

/* After the first detection: every force restored from the sample should have found its contact (a pair within the
   alert distance, keyed as in the file); those that did not start from zero, which a wrong file would otherwise hide. */
static PetscErrorCode StepperCheckSampleForces(KergsStepper st)
{
  KergsContact *c;
  PetscInt      m, matched = 0;
  const char   *path;

  PetscFunctionBeginUser;
  PetscCall(KergsContactsGetLocal(st->contacts, &m, &c));
  for (PetscInt k = 0; k < m; k++) matched += c[k].persistent ? 1 : 0;
  PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, &matched, 1, MPIU_INT, MPI_SUM, st->comm));
  PetscCall(KergsSceneGetSamplePath(st->scene, &path));
  if (matched < st->sample_nforces)
    PetscCall(PetscPrintf(st->comm,
                          "kergs: warning: %" PetscInt_FMT " of the %" PetscInt_FMT
                          " contact forces of sample file %s match no contact of the "
                          "first step (their grains are not within the alert distance): they start from zero\n",
                          st->sample_nforces - matched, st->sample_nforces, path));
  PetscCall(PetscInfo(NULL, "%" PetscInt_FMT " of the %" PetscInt_FMT " contact forces of sample file %s are the first step's warm start\n",
                      matched, st->sample_nforces, path));
  PetscFunctionReturn(0);
}

/* The automatic alert distance for this step (KergsSceneAdaptAlert) from the fastest closing speed at its start: two
   grains at the fastest grain's speed vmax, or that grain and the fastest wall. */
static PetscErrorCode StepperAdaptAlert(KergsStepper st, PetscReal vmax)
{
  const KergsWall *walls;
  PetscInt         nwalls;
  PetscReal        vwall = 0.0;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  for (PetscInt w = 0; w < nwalls; w++) vwall = PetscMax(vwall, PetscSqrtReal(PetscSqr(walls[w].v[0]) + PetscSqr(walls[w].v[1])));
  PetscCall(KergsSceneAdaptAlert(st->scene, PetscMax(2.0 * vmax, vmax + vwall)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperStep(KergsStepper st)
{
  KergsScene      sc = st->scene;
  KergsSolveStats ss;
  PetscLogDouble  t0, t1, t2;
  PetscReal      *vold, *wold, *wvold;
  PetscBool       due, keepH, needsH, needsFullW, needsBoth, stop;
  PetscInt        step;
  PetscReal       vmax;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&st->step_start));
  PetscCall(KergsStepperEnergy(st, &st->ek_start, &vmax));
  PetscCall(StepperAdaptAlert(st, vmax));
  st->sent_start = petsc_send_len + petsc_isend_len;
  PetscCall(KergsSceneGetStep(sc, &step, NULL, NULL));
  /* initial partition before the first detection, then checks every -partition_check_every steps, with the
     contacts of the previous step (after its solve): migrates the disks and their contacts when due */
  PetscCall(KergsPartitionUpdate(st->partition, sc, st->contacts, NULL));
  if (step == 0 && st->sample_forces && !st->restart_path[0]) PetscCall(KergsSampleReadForces(sc, st->contacts, &st->sample_nforces));
  PetscCall(PetscTime(&t0));
  PetscCall(KergsContactsDetect(st->contacts, sc));
  if (step == 0) PetscCall(CheckInitialOverlaps(st));
  if (step == 0 && st->sample_nforces) PetscCall(StepperCheckSampleForces(st));
  PetscCall(PetscTime(&t1));
  /* v^d, then W: unless kept, H is freed before W exists, built again for the update once W is freed, and freed after
     it. W couples the active contacts only, unless the solver works on the whole W (the kernel-regularised types). */
  PetscCall(KergsSolverNeedsH(st->solver, &needsH));
  PetscCall(KergsSolverNeedsFullW(st->solver, &needsFullW));
  PetscCall(KergsSolverNeedsBothTriangles(st->solver, &needsBoth));
  PetscCall(KergsOperatorsSetBothTriangles(st->ops, needsBoth));
  keepH = (PetscBool)(st->keep_H || needsH);
  PetscCall(KergsOperatorsAssembleH(st->ops, sc, st->contacts, keepH));
  PetscCall(KergsOperatorsAssembleW(st->ops, sc, st->contacts, (PetscBool)!needsFullW));
  PetscCall(KergsOperatorsGetImpulses(st->ops, st->contacts)); /* warm start */
  PetscCall(PetscTime(&t2));
  PetscCall(KergsSolverSetStepNumber(st->solver, step + 1)); /* numbered as the step lines, for -solver_monitor */
  PetscCall(KergsSolverSolve(st->solver, sc, st->contacts, st->ops, &ss));
  stop = (PetscBool)(ss.reason == KERGS_SOLVER_DIVERGED_INFEASIBLE && !st->on_infeasible_continue);
  /* the contacts keep this step's impulses (the export reads them there), unless the step is not applied */
  if (!stop || step + 1 == st->fclib_step) PetscCall(KergsOperatorsSetImpulses(st->ops, st->contacts));
  if (step + 1 == st->fclib_step) { /* the step that the line "step N" reports: N = step + 1 */
    const PetscBool *active;
    PetscCall(KergsSolverGetActive(st->solver, &active));
    PetscCall(KergsFCLibExport(sc, st->contacts, st->ops, active, st->fclib_path));
  }
  if (stop) {
    /* no answer to apply: the state, the contacts' impulses and the results stay those of the previous step */
    PetscCall(KergsStepperReportInfeasible(st, step + 1));
    PetscCall(KergsOperatorsReleaseW(st->ops));
    PetscCall(KergsOperatorsReleaseH(st->ops));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscLogEventBegin(KERGS_Update, 0, 0, 0, 0));
  if (!keepH) {
    PetscCall(KergsOperatorsReleaseW(st->ops));
    PetscCall(KergsOperatorsBuildHf(st->ops, sc, st->contacts));
  }
  PetscCall(SaveVelocities(sc, &vold, &wold, &wvold));
  PetscCall(KergsOperatorsUpdateVelocities(st->ops, sc));
  PetscCall(KergsStepperExternalWork(st, vold, wvold, &st->work, &st->driven_work));
  if (!keepH) PetscCall(KergsOperatorsReleaseH(st->ops));
  PetscCall(KergsSceneAdvance(sc, vold, wold, wvold));
  PetscCall(PetscFree3(vold, wold, wvold));
  /* the ghosts' new state, for the measures and the next detection (which rebuilds the layer after a migration or
     once a disk moved half the skin) */
  PetscCall(KergsSceneRefreshGhosts(sc));
  PetscCall(PetscLogEventEnd(KERGS_Update, 0, 0, 0, 0));
  st->io_seconds = 0;
  PetscCall(KergsResultsSnapshotDue(st->results, step + 1, PETSC_FALSE, &due)); /* the last one is KergsStepperRun's */
  if (due) {
    PetscLogDouble t3, t4;
    PetscCall(PetscTime(&t3));
    PetscCall(KergsResultsSnapshot(st->results, sc, st->contacts));
    PetscCall(PetscTime(&t4));
    st->io_seconds = t4 - t3;
  }
  PetscCall(KergsStepperEnergy(st, &st->ek_end, &st->vmax_end));
  PetscCall(KergsStepperRecordStep(st, &ss, t1 - t0, t2 - t1));
  PetscCall(KergsStepperWatch(st, &ss));
  PetscFunctionReturn(0);
}

/* The end of the run's summary: why it ended */
static const char *EndText(KergsStepper st, PetscBool rest, char buf[], size_t len)
{
  switch (st->status) {
  case KERGS_EXIT_BLOWUP:
  case KERGS_EXIT_SOLVER_FAILED:
    (void)PetscSNPrintf(buf, len, "%s: %s", st->status == KERGS_EXIT_BLOWUP ? "blow-up" : "solver failure",
                        st->failure_kind ? st->failure_kind : "non-finite state");
    return buf;
  case KERGS_EXIT_SIGNAL:
    (void)PetscSNPrintf(buf, len, "stopped by %s", KergsSignalName(st->signal));
    return buf;
  default:
    return rest ? "done (at rest)" : "done";
  }
}

/* At rest: every grain slower than -stop_at_rest, or the kinetic energy per grain below -stop_at_rest_energy, once the
   packing has been set in motion - its energy per grain above -stop_at_rest_energy when that is given (a compaction's
   first steps are slower than any useful speed rule allows but not yet moving: 20,000 grains start at 2e-9 J/m each),
   else a grain faster than -stop_at_rest. The energy rule is for solvers stopped at a loose tolerance (NLGS to quad
   1e-4), whose answers keep a few grains of a 5,000-disk packing at rest above any useful speed threshold while the
   energy per grain is 4e-6 of p d^2 (docs/biaxial.md). Or the box's inertial number over the last -stop_at_rest_window
   steps below -stop_at_rest_inertial, once it has been above: the walls have stopped closing in, whatever rattlers
   still move (the guard: heavy walls start so slowly that the first window could measure them at rest), with the
   Love-Weber stress inside and the walls', averaged over the window, within -stop_at_rest_stress p of each other: the
   walls of a large sample jam while the grains inside are still out of equilibrium (100,000 disks: 1.34 p in the step
   where the rule alone stopped, docs/biaxial.md). */
static PetscErrorCode StepperAtRest(KergsStepper st, PetscBool *rest)
{
  KergsDisks D;
  PetscReal  ek, vmax, per_grain;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneKineticEnergy(st->scene, &ek, &vmax));
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  per_grain = D.ndisks > 0 ? ek / D.ndisks : 0.0;
  if (st->rest_energy > 0 ? per_grain >= st->rest_energy : vmax >= st->rest_speed) st->moved = PETSC_TRUE;
  *rest = (PetscBool)(st->moved && ((st->rest_speed > 0 && vmax < st->rest_speed) || (st->rest_energy > 0 && per_grain < st->rest_energy)));
  if (!*rest && st->inertial_armed && st->box_inertial >= 0 && st->box_inertial < st->rest_inertial &&
      (!(st->rest_stress > 0) || (st->box_stress_gap >= 0 && st->box_stress_gap <= st->rest_stress))) {
    *rest = PETSC_TRUE;
    if (st->rest_stress > 0)
      PetscCall(PetscPrintf(st->comm,
                            "kergs: at rest by the inertial number: I = %.3g below %g over the last %" PetscInt_FMT
                            " steps, and the Love-Weber stress, averaged over them, within %.2g p of the walls' (in equilibrium)\n",
                            (double)st->box_inertial, (double)st->rest_inertial, st->rest_window, (double)st->box_stress_gap));
    else /* the gap is recorded but was not compared: no claim of equilibrium */
      PetscCall(PetscPrintf(st->comm,
                            "kergs: at rest by the inertial number alone: I = %.3g below %g over the last %" PetscInt_FMT
                            " steps (-stop_at_rest_stress 0: the stress inside was not compared with the walls')\n",
                            (double)st->box_inertial, (double)st->rest_inertial, st->rest_window));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperRun(KergsStepper st)
{
  KergsScene        sc = st->scene;
  KergsResultsState rs;
  KergsPoll         poll;
  PetscReal         ek, vmax;
  PetscBool         rest = PETSC_FALSE, enabled, stopped = PETSC_FALSE;
  PetscViewer       view;
  PetscInt          step, nsteps, max_it;
  const char       *counted;
  const char       *path;
  char              end[64];

  PetscFunctionBeginUser;
  st->status = KERGS_EXIT_DONE;
  PetscCall(KergsSceneGetStep(sc, &step, NULL, &nsteps));
  if (step == 0) PetscCall(KergsStepperCheckContainer(st)); /* before any file is written */
  PetscCall(KergsStepperWarnInertialNumber(st));
  PetscCheck(st->fclib_step <= nsteps, st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-fclib_step %" PetscInt_FMT " is beyond the run (-steps %" PetscInt_FMT "): no such step to export", st->fclib_step, nsteps);
  PetscCall(KergsStepperEnergyFloor(st));
  PetscCall(KergsStepperStartBox(st));
  PetscCall(KergsStepperCatchSignals(PETSC_TRUE));
  PetscCall(KergsResultsOpen(st->results));
  PetscCall(KergsResultsGetState(st->results, &rs));
  if (rs.nsnapshots == 0) PetscCall(KergsResultsSnapshot(st->results, sc, st->contacts)); /* a continued file has its first one */
  PetscCall(KergsSceneGetStep(sc, &step, NULL, &nsteps));
  PetscCall(PetscTime(&st->loop_start));
  st->last_progress = st->last_checkpoint = st->loop_start;
  st->progress_step = st->loop_start_step = step;
  for (;;) {
    PetscBool due;
    /* between two steps (and before the first): a signal, a blow-up, a checkpoint due, agreed by every rank */
    PetscCall(KergsStepperPoll(st, &poll));
    if (poll.blowup) {
      st->status = KERGS_EXIT_BLOWUP;
      if (poll.blowup_grain >= 0)
        PetscCall(PetscPrintf(
            st->comm, "kergs: blow-up after step %" PetscInt_FMT ": grain %" PetscInt_FMT " has a non-finite position or velocity\n", step,
            poll.blowup_grain));
      else
        PetscCall(
            PetscPrintf(st->comm, "kergs: blow-up after step %" PetscInt_FMT ": a wall has a non-finite position or velocity\n", step));
      break; /* no checkpoint of a broken state: the last one stays */
    }
    due = (PetscBool)(poll.signal || poll.checkpoint_time || (st->checkpoint_every > 0 && step % st->checkpoint_every == 0 && step > 0));
    if (due) PetscCall(KergsStepperCheckpoint(st));
    if (poll.signal) {
      st->status = KERGS_EXIT_SIGNAL;
      st->signal = poll.signal;
      PetscCall(PetscPrintf(st->comm, "kergs: %s received: stopped after step %" PetscInt_FMT "\n", KergsSignalName(poll.signal), step));
      stopped = PETSC_TRUE;
      break;
    }
    if (step >= nsteps || rest) break;
    PetscCall(KergsStepperStep(st));
    PetscCall(KergsSceneGetStep(sc, &step, NULL, NULL));
    if (st->failure[0]) { /* the watch's verdict, the same on every rank; no checkpoint of a broken state */
      st->status = st->failure_status;
      PetscCall(PetscPrintf(st->comm, "kergs: %s\n", st->failure));
      break;
    }
    if (st->rest_speed > 0 || st->rest_energy > 0 || st->rest_inertial > 0) PetscCall(StepperAtRest(st, &rest));
    PetscCall(KergsStepperProgress(st, PETSC_FALSE));
  }
  /* a finished run leaves a checkpoint too when asked for them, to be continued with a larger -steps; taken before the
     last snapshot, as a checkpoint inside the loop is, so that a continuation writes the snapshots of one long run */
  if (st->status == KERGS_EXIT_DONE && st->checkpointing) PetscCall(KergsStepperCheckpoint(st));
  PetscCall(KergsResultsSnapshot(st->results, sc, st->contacts));
  PetscCall(KergsResultsSetEnd(st->results, EndText(st, rest, end, sizeof(end))));
  PetscCall(KergsResultsClose(st->results));
  /* the handler stays until KergsStepperDestroy: a signal now (Slurm's warning at the end of a run that has just
     finished) finds the run's work done and changes nothing, instead of ending the process with status 128 + signal */
  if (st->sample_out[0] && st->status == KERGS_EXIT_DONE)
    PetscCall(KergsSampleWrite(sc, st->contacts, st->sample_out)); /* a finished packing only */
  if (st->status == KERGS_EXIT_DONE && st->error_on_nonconvergence && st->nonconverged > 0) st->status = KERGS_EXIT_NOT_CONVERGED;
  PetscCall(KergsSceneKineticEnergy(sc, &ek, &vmax));
  PetscCall(KergsSolverGetTolerances(st->solver, NULL, &max_it));
  PetscCall(KergsSolverGetIterationName(st->solver, &counted));
  if (stopped || st->progress_every || st->progress_seconds) PetscCall(KergsStepperProgress(st, PETSC_TRUE));
  PetscCall(PetscPrintf(st->comm,
                        "kergs: %" PetscInt_FMT " steps%s, %" PetscInt_FMT " not converged (cap %" PetscInt_FMT
                        " %s), largest interpenetration %.3g, kinetic energy %.3g, fastest grain %.3g\n",
                        step, rest ? " (at rest)" : "", st->nonconverged, max_it, counted, (double)st->max_violation, (double)ek,
                        (double)vmax));
  PetscCall(KergsPartitionGetView(st->partition, &view));
  if (view) PetscCall(KergsPartitionView(st->partition, view));
  PetscCall(KergsResultsGetPath(st->results, &path, &enabled));
  if (enabled) PetscCall(PetscPrintf(st->comm, "kergs: results in %s\n", path));
  PetscCall(KergsResultsGetXdmfPath(st->results, &path));
  if (path[0]) PetscCall(PetscPrintf(st->comm, "kergs: for ParaView (XDMF Reader) %s\n", path));
  if (st->sample_out[0] && st->status != KERGS_EXIT_SIGNAL && st->status != KERGS_EXIT_BLOWUP)
    PetscCall(PetscPrintf(st->comm, "kergs: sample in %s\n", st->sample_out));
  if (st->fclib_step >= 1 && st->fclib_step <= step)
    PetscCall(PetscPrintf(st->comm, "kergs: FCLib problem of step %" PetscInt_FMT " in %s\n", st->fclib_step, st->fclib_path));
  if (st->checkpoint_step >= 0 && (st->checkpointing || stopped))
    PetscCall(PetscPrintf(st->comm, "kergs: checkpoint of step %" PetscInt_FMT " in %s\n", st->checkpoint_step, st->checkpoint_path));
  PetscCall(PetscPrintf(st->comm, "kergs: %s, exit status %d\n", EndText(st, rest, end, sizeof(end)), (int)st->status));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperGetExitStatus(KergsStepper st, KergsExitStatus *status)
{
  PetscFunctionBeginUser;
  *status = st->status;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperDestroy(KergsStepper *st)
{
  PetscFunctionBeginUser;
  if (!*st) PetscFunctionReturn(0);
  PetscCall(KergsStepperCatchSignals(PETSC_FALSE));
  PetscCall(PetscFree((*st)->box_track));
  PetscCall(KergsPartitionDestroy(&(*st)->partition));
  PetscCall(KergsResultsDestroy(&(*st)->results));
  PetscCall(KergsSolverDestroy(&(*st)->solver));
  PetscCall(KergsOperatorsDestroy(&(*st)->ops));
  PetscCall(KergsContactsDestroy(&(*st)->contacts));
  PetscCall(KergsSceneDestroy(&(*st)->scene));
  PetscCall(PetscFree(*st));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperGetScene(KergsStepper st, KergsScene *scene)
{
  PetscFunctionBeginUser;
  *scene = st->scene;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperGetContacts(KergsStepper st, KergsContacts *contacts)
{
  PetscFunctionBeginUser;
  *contacts = st->contacts;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperGetOperators(KergsStepper st, KergsOperators *ops)
{
  PetscFunctionBeginUser;
  *ops = st->ops;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperGetSolver(KergsStepper st, KergsSolver *solver)
{
  PetscFunctionBeginUser;
  *solver = st->solver;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperGetResults(KergsStepper st, KergsResults *results)
{
  PetscFunctionBeginUser;
  *results = st->results;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperGetPartition(KergsStepper st, KergsPartition *partition)
{
  PetscFunctionBeginUser;
  *partition = st->partition;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperGetRunSummary(KergsStepper st, PetscInt *nonconverged, PetscReal *max_violation)
{
  PetscFunctionBeginUser;
  if (nonconverged) *nonconverged = st->nonconverged;
  if (max_violation) *max_violation = st->max_violation;
  PetscFunctionReturn(0);
}
