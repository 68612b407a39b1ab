/* kergs stepper: the statistics of a step. Every component returns what it measured in a struct (the solve's
   KergsSolveStats with its type's own figures, the partition's measures, the operators' sizes); this file hands them
   to the results writer, the one place where io happens, and prints the step's summary line. */
#include <kergs/private/stepperimpl.h>
#include <sys/resource.h>

PetscErrorCode KergsStepperPeakMemory(MPI_Comm comm, PetscReal *bytes)
{
  struct rusage ru;
  PetscReal     mine;

  PetscFunctionBeginUser;
  getrusage(RUSAGE_SELF, &ru);
  mine = 1024.0 * (PetscReal)ru.ru_maxrss; /* Linux reports kilobytes */
  PetscCall(MPIU_Allreduce(&mine, bytes, 1, MPIU_REAL, MPI_SUM, comm));
  PetscFunctionReturn(0);
}

/* Interpenetration at the end of the step, from the exact gaps of this step's active contact pairs at the new
   positions: mean over active contacts of max(0, -g+), the largest, and the largest relative to the smaller radius of
   the pair (the watch's -blowup_overlap). Global. */
static PetscErrorCode MeasureViolation(KergsStepper st, PetscReal *mean, PetscReal *max, PetscReal *maxrel, PetscInt *nactive)
{
  KergsDisks       D;
  const KergsWall *walls;
  const PetscBool *active;
  KergsContact    *c;
  PetscInt         n, lact = 0;
  PetscReal        loc[2] = {0, 0}, glob[2], lmax[2] = {0, 0}, gmax[2];

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  PetscCall(KergsSceneGetWalls(st->scene, NULL, &walls));
  PetscCall(KergsContactsGetLocal(st->contacts, &n, &c));
  PetscCall(KergsSolverGetActive(st->solver, &active));
  for (PetscInt k = 0; k < n; k++) {
    const PetscReal *xa = &D.x[KERGS_DIM * c[k].a];
    PetscReal        g;
    if (!active[k]) continue;
    if (c[k].kind == KERGS_CONTACT_DISK_DISK) {
      const PetscReal *xb = &D.x[KERGS_DIM * c[k].b];
      PetscReal        d2 = 0;
      for (PetscInt d = 0; d < KERGS_DIM; d++) d2 += (xa[d] - xb[d]) * (xa[d] - xb[d]);
      g = PetscSqrtReal(d2) - c[k].ra - c[k].rb;
    } else {
      const KergsWall *w = &walls[c[k].b];
      g                  = -c[k].ra;
      for (PetscInt d = 0; d < KERGS_DIM; d++) g += (xa[d] - w->a[d]) * c[k].n[d];
    }
    lact++;
    loc[0] += PetscMax(0.0, -g);
    lmax[0] = PetscMax(lmax[0], -g);
    lmax[1] = PetscMax(lmax[1], -g / (c[k].kind == KERGS_CONTACT_DISK_DISK ? PetscMin(c[k].ra, c[k].rb) : c[k].ra));
  }
  loc[1] = (PetscReal)lact;
  PetscCall(MPIU_Allreduce(loc, glob, 2, MPIU_REAL, MPI_SUM, st->comm));
  PetscCall(MPIU_Allreduce(lmax, gmax, 2, MPIU_REAL, MPIU_MAX, st->comm));
  *mean    = glob[1] > 0 ? glob[0] / glob[1] : 0.0;
  *max     = gmax[0];
  *maxrel  = gmax[1];
  *nactive = (PetscInt)glob[1];
  PetscFunctionReturn(0);
}

/* "-6:DIVERGED_NANORINF,...,4:CONVERGED_NO_CONTACTS": the attribute that names converged_reason's values */
static PetscErrorCode ReasonNames(char names[], size_t len)
{
  size_t used = 0;

  PetscFunctionBeginUser;
  names[0] = 0;
  for (PetscInt r = KERGS_SOLVER_REASON_MIN; r <= KERGS_SOLVER_REASON_MAX; r++) {
    PetscCall(PetscSNPrintf(names + used, len - used, "%s%" PetscInt_FMT ":%s", r > KERGS_SOLVER_REASON_MIN ? "," : "", r,
                            KergsSolverConvergedReasons[r]));
    PetscCall(PetscStrlen(names, &used));
  }
  PetscFunctionReturn(0);
}

/* The solve's statistics: common figures, then the type's own figures and texts. converged is 1 when the reason is
   positive: the column the scripts count. */
PetscErrorCode KergsStepperRecordSolve(KergsResults res, const KergsSolveStats *ss)
{
  char names[512];

  PetscFunctionBeginUser;
  PetscCall(ReasonNames(names, sizeof(names)));
  PetscCall(KergsResultsRecord(res, "iterations", (PetscReal)ss->iterations));
  PetscCall(KergsResultsRecord(res, "converged", ss->reason > 0 ? 1.0 : 0.0));
  PetscCall(KergsResultsRecord(res, "converged_reason", (PetscReal)ss->reason));
  PetscCall(KergsResultsRecordStatisticText(res, "converged_reason", "names", names));
  PetscCall(KergsResultsRecord(res, "residual", ss->residual));
  PetscCall(KergsResultsRecord(res, "velocity_error", ss->velocity_error));
  PetscCall(KergsResultsRecord(res, "criterion", ss->criterion));
  PetscCall(KergsResultsRecord(res, "solve_seconds", ss->seconds));
  PetscCall(KergsResultsRecord(res, "sweep_seconds", ss->sweep_seconds));
  for (PetscInt i = 0; i < ss->nextra; i++) PetscCall(KergsResultsRecord(res, ss->extra[i].name, ss->extra[i].value));
  for (PetscInt i = 0; i < ss->ntext; i++) PetscCall(KergsResultsRecordText(res, ss->text[i].name, ss->text[i].value));
  PetscFunctionReturn(0);
}

static PetscErrorCode RecordPartition(KergsResults res, const KergsPartitionMeasures *m)
{
  PetscFunctionBeginUser;
  PetscCall(KergsResultsRecord(res, "edge_cut", (PetscReal)m->edgecut));
  PetscCall(KergsResultsRecord(res, "imbalance", m->imbalance));
  PetscCall(KergsResultsRecord(res, "ghosts", (PetscReal)m->ghosts));
  PetscCall(KergsResultsRecord(res, "repartitions", (PetscReal)m->repartitions));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperRecordStep(KergsStepper st, const KergsSolveStats *ss, PetscLogDouble tdetect, PetscLogDouble tassemble)
{
  KergsResults           res = st->results;
  KergsPartitionMeasures pm;
  KergsSolverType        type;
  PetscReal mean = 0, max = 0, maxrel = 0, times[4] = {tdetect, tassemble, st->io_seconds, 0}, tmax[4], peak, sent, nnz_Hf, nnz_W, time;
  PetscInt  nactive = 0, step, ncontacts;
  PetscLogDouble now;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&now));
  times[3] = now - st->step_start;
  /* point-to-point and personalised collective bytes (PETSc's MPI logging; reductions are counted, not sized) */
  sent = (PetscReal)(petsc_send_len + petsc_isend_len - st->sent_start);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sent, 1, MPIU_REAL, MPIU_SUM, st->comm));
  PetscCall(MeasureViolation(st, &mean, &max, &maxrel, &nactive));
  PetscCall(MPIU_Allreduce(times, tmax, 4, MPIU_REAL, MPI_MAX, st->comm));
  PetscCall(KergsStepperPeakMemory(st->comm, &peak));
  PetscCall(KergsSceneGetStep(st->scene, &step, &time, NULL));
  PetscCall(KergsContactsGetGlobalRange(st->contacts, NULL, &ncontacts));
  PetscCall(KergsOperatorsGetNonzeros(st->ops, &nnz_Hf, &nnz_W));
  PetscCall(KergsPartitionObserve(st->partition, st->scene, st->contacts, ss->sweep_seconds, ss->compute_seconds, &pm));
  PetscCall(KergsSolverGetType(st->solver, &type));
  st->max_violation = PetscMax(st->max_violation, max);
  if (ss->reason <= 0) st->nonconverged++;
  st->last_contacts      = ncontacts;
  st->last_sweeps        = ss->iterations;
  st->last_residual      = ss->residual;
  st->last_max_violation = max;
  st->last_max_relative  = maxrel;
  PetscCall(KergsResultsRecordText(res, "solver_type", type));
  PetscCall(KergsResultsRecord(res, "step", (PetscReal)step));
  PetscCall(KergsResultsRecord(res, "time", time));
  PetscCall(KergsResultsRecord(res, "contacts", (PetscReal)ncontacts));
  PetscCall(KergsResultsRecord(res, "active", (PetscReal)nactive));
  PetscCall(KergsResultsRecord(res, "mean_violation", mean));
  PetscCall(KergsResultsRecord(res, "max_violation", max));
  PetscCall(KergsResultsRecord(res, "max_relative_violation", maxrel));
  PetscCall(KergsResultsRecord(res, "kinetic_energy", st->ek_end));
  PetscCall(KergsResultsRecord(res, "external_work", st->work));
  PetscCall(KergsResultsRecord(res, "detect_seconds", tmax[0]));
  PetscCall(KergsResultsRecord(res, "assemble_seconds", tmax[1]));
  PetscCall(KergsResultsRecord(res, "io_seconds", tmax[2]));
  PetscCall(KergsResultsRecord(res, "step_seconds", tmax[3]));
  PetscCall(KergsResultsRecord(res, "sent_bytes", sent));
  PetscCall(KergsResultsRecord(res, "peak_memory", peak));
  PetscCall(KergsResultsRecord(res, "baseline_memory", st->baseline_rss));
  PetscCall(KergsResultsRecord(res, "nnz_Hf", nnz_Hf));
  PetscCall(KergsResultsRecord(res, "nnz_W", nnz_W));
  PetscCall(KergsStepperRecordSolve(res, ss));
  PetscCall(RecordPartition(res, &pm));
  PetscCall(KergsStepperRecordMacro(st));
  if (st->rest_inertial > 0) PetscCall(KergsStepperTrackBox(st));
  PetscCall(KergsResultsEndStep(res));
  if (!st->quiet)
    PetscCall(PetscPrintf(st->comm,
                          "step %5" PetscInt_FMT " t %-10.5g contacts %6" PetscInt_FMT " active %6" PetscInt_FMT " sweeps %4" PetscInt_FMT
                          "%s residual %8.2e violation mean %8.2e max %8.2e solve %.3g s\n",
                          step, (double)time, ncontacts, nactive, ss->iterations, ss->reason > 0 ? "  " : " !", (double)ss->residual,
                          (double)mean, (double)max, (double)ss->seconds));
  PetscFunctionReturn(0);
}
