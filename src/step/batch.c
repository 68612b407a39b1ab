/* kergs stepper: batch use (docs/running.md). The options of checkpoints, restarts and progress lines; the checks of
   the run's paths; signals (a handler sets a flag, the time loop polls it between steps, agreed across ranks by one
   reduction that also catches a blown-up state and the wall-clock checkpoint); checkpoints and progress lines. */
#include <kergs/private/stepperimpl.h>
#include <kergs/checkpoint.h>
#include <signal.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------------ */
/* Options                                                                                          */

PetscErrorCode KergsStepperBatchOptions(KergsStepper st)
{
  PetscBool every, seconds, path;

  PetscFunctionBeginUser;
  PetscOptionsBegin(st->comm, NULL, "Batch options: checkpoints, restart, progress lines (docs/running.md)", NULL);
  PetscCall(PetscOptionsString("-restart",
                               "Continue the run of this checkpoint file (its options are this run's; the command line overrides them)",
                               "KergsCheckpointRead", st->restart_path, st->restart_path, sizeof(st->restart_path), NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-checkpoint_every", "Write a checkpoint every N steps (0: not by steps)",
                            "KergsCheckpointWrite", st->checkpoint_every, &st->checkpoint_every, &every));
  PetscCall(PetscOptionsReal("-checkpoint_seconds", "Write a checkpoint every T seconds of wall time (0: not by time)",
                             "KergsCheckpointWrite", st->checkpoint_seconds, &st->checkpoint_seconds, &seconds));
  PetscCall(PetscOptionsString("-checkpoint_path",
                               "Checkpoint file, written atomically (default: the results file's name with .checkpoint.h5; also written "
                               "on SIGTERM, SIGINT, SIGUSR1)",
                               "KergsCheckpointWrite", st->checkpoint_path, st->checkpoint_path, sizeof(st->checkpoint_path), &path));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-progress_every", "Print a progress line every N steps (0: not by steps)", "",
                            st->progress_every, &st->progress_every, NULL));
  PetscCall(PetscOptionsReal("-progress_seconds", "Print a progress line every T seconds of wall time (0: not by time)", "",
                             st->progress_seconds, &st->progress_seconds, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-error_on_nonconvergence", "Exit with status 3 at the end if some step did not converge",
                             "", st->error_on_nonconvergence, &st->error_on_nonconvergence, NULL));
  PetscOptionsEnd();
  PetscCheck(st->checkpoint_every >= 0, st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-checkpoint_every %" PetscInt_FMT " must be >= 0 (0: not by steps)", st->checkpoint_every);
  PetscCheck(st->checkpoint_seconds >= 0 && !PetscIsInfOrNanReal(st->checkpoint_seconds), st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-checkpoint_seconds %g must be a non-negative number of seconds", (double)st->checkpoint_seconds);
  PetscCheck(st->progress_every >= 0, st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-progress_every %" PetscInt_FMT " must be >= 0 (0: not by steps)", st->progress_every);
  PetscCheck(st->progress_seconds >= 0 && !PetscIsInfOrNanReal(st->progress_seconds), st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-progress_seconds %g must be a non-negative number of seconds", (double)st->progress_seconds);
  PetscCheck(!path || st->checkpoint_path[0], st->comm, PETSC_ERR_ARG_WRONG, "Option -checkpoint_path needs a file name");
  st->checkpointing = (PetscBool)(every || seconds || path);
  PetscFunctionReturn(0);
}

/* -checkpoint_path's default: next to the results file, <output without .h5>.checkpoint.h5. */
PetscErrorCode KergsStepperDefaultCheckpointPath(KergsStepper st)
{
  const char *out;
  size_t      n;

  PetscFunctionBeginUser;
  if (st->checkpoint_path[0]) PetscFunctionReturn(0);
  PetscCall(KergsResultsGetPath(st->results, &out, NULL));
  PetscCall(PetscStrlen(out, &n));
  if (n > 3 && !strcmp(out + n - 3, ".h5")) n -= 3;
  PetscCall(PetscSNPrintf(st->checkpoint_path, sizeof(st->checkpoint_path), "%.*s.checkpoint.h5", (int)n, out));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsInputFilesAdd(MPI_Comm comm, KergsInputFiles *in, const char option[], const char path[])
{
  PetscFunctionBeginUser;
  PetscCheck(in->n < KERGS_STEPPER_MAXINPUTS, comm, PETSC_ERR_ARG_OUTOFRANGE, "At most %d input files of %s", KERGS_STEPPER_MAXINPUTS,
             option);
  PetscCall(PetscStrncpy(in->option[in->n], option, sizeof(in->option[0])));
  PetscCall(PetscStrncpy(in->path[in->n], path, sizeof(in->path[0])));
  in->n++;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperAddInput(KergsStepper st, const char option[], const char path[])
{
  PetscFunctionBeginUser;
  PetscCall(KergsInputFilesAdd(st->comm, &st->inputs, option, path));
  PetscFunctionReturn(0);
}

/* Every output of the run against every input and the others, before the run starts (KergsFileCheckPaths). */
PetscErrorCode KergsStepperCheckPaths(KergsStepper st)
{
  static const char *const same[][2] = {{"-checkpoint_path", "-restart"}}; /* read whole first, replaced atomically later */
  char                     sample_in[PETSC_MAX_PATH_LEN] = "";
  const char              *out, *xdmf;
  PetscBool                enabled, set;
  KergsFileRole            outputs[5], inputs[2 + KERGS_STEPPER_MAXINPUTS];
  PetscInt                 nin = 0;

  PetscFunctionBeginUser;
  PetscCall(KergsResultsGetPath(st->results, &out, &enabled));
  PetscCall(KergsResultsGetXdmfPath(st->results, &xdmf));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-sample_input", sample_in, sizeof(sample_in), &set));
  outputs[0]    = (KergsFileRole){"-output", enabled ? out : NULL};
  outputs[1]    = (KergsFileRole){"-sample_output", st->sample_out};
  outputs[2]    = (KergsFileRole){"-fclib_output", st->fclib_step >= 1 ? st->fclib_path : NULL};
  outputs[3]    = (KergsFileRole){"-checkpoint_path", st->checkpoint_path};
  outputs[4]    = (KergsFileRole){"-output_xdmf", xdmf};                                    /* <output without .h5>.xdmf */
  inputs[nin++] = (KergsFileRole){"-sample_input", st->restart_path[0] ? NULL : sample_in}; /* a restart does not read it */
  inputs[nin++] = (KergsFileRole){"-restart", st->restart_path};
  for (PetscInt k = 0; k < st->inputs.n; k++) inputs[nin++] = (KergsFileRole){st->inputs.option[k], st->inputs.path[k]};
  PetscCall(KergsFileCheckPaths(st->comm, 5, outputs, nin, inputs, 1, same));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Signals                                                                                          */

static const int Caught[] = {SIGTERM, SIGINT, SIGUSR1};
#define NCAUGHT ((int)(sizeof(Caught) / sizeof(Caught[0])))
static struct sigaction      Saved[NCAUGHT];
static volatile sig_atomic_t Received  = 0; /* the first signal, the stop request */
static volatile sig_atomic_t Seen      = 0; /* every kind received since, one bit per kind */
static PetscBool             Installed = PETSC_FALSE;

/* The first signal asks for a clean stop after the step. The first signal of each other kind is ignored: it is the
   same request relayed (a terminal's Ctrl-C sends SIGINT to mpiexec and the ranks, and mpiexec then sends the ranks
   SIGTERM, which used to kill them and leave only .tmp files). A second SIGTERM or SIGINT, whatever came first, ends
   the process at once, as without kergs's handler. A second SIGUSR1 is ignored too: a batch system's warning that
   reaches the ranks both directly and through mpiexec (a job script that forwards it) arrives twice, and killed the
   ranks before their checkpoint. Only async-signal-safe calls. */
static void OnSignal(int sig)
{
  const int bit = sig == SIGTERM ? 1 : sig == SIGINT ? 2 : 4;

  if ((Seen & bit) && sig != SIGUSR1) {
    (void)signal(sig, SIG_DFL);
    (void)raise(sig);
    return;
  }
  Seen |= bit;
  if (!Received) Received = sig;
}

int KergsStepperCatchStopSignals(PetscBool on)
{
  int failed = 0;

  if (!on) {
    if (Installed)
      for (int k = 0; k < NCAUGHT; k++) (void)sigaction(Caught[k], &Saved[k], NULL);
    Installed = PETSC_FALSE;
    return 0;
  }
  if (!Installed) Received = Seen = 0;
  for (int k = 0; k < NCAUGHT; k++) {
    struct sigaction sa, cur;
    if (!sigaction(Caught[k], NULL, &cur) && cur.sa_handler == OnSignal) continue; /* still ours */
    memset(&sa, 0, sizeof(sa));
    sa.sa_handler = OnSignal;
    sigemptyset(&sa.sa_mask);
    failed |= sigaction(Caught[k], &sa, Installed ? NULL : &Saved[k]); /* the disposition found before kergs's, once */
  }
  Installed = PETSC_TRUE;
  return failed;
}

PetscErrorCode KergsStepperCatchSignals(PetscBool on)
{
  PetscFunctionBeginUser;
  PetscCheck(!KergsStepperCatchStopSignals(on), PETSC_COMM_SELF, PETSC_ERR_SYS,
             "Cannot install the handlers of SIGTERM, SIGINT and SIGUSR1");
  PetscFunctionReturn(0);
}

const char *KergsSignalName(int sig)
{
  return sig == SIGTERM ? "SIGTERM" : sig == SIGINT ? "SIGINT" : sig == SIGUSR1 ? "SIGUSR1" : "a signal";
}

PetscInt KergsStepperFirstNonFiniteGrain(KergsScene sc)
{
  KergsDisks       D;
  const KergsWall *walls;
  PetscInt         nwalls;

  if (KergsSceneGetDisks(sc, &D) || KergsSceneGetWalls(sc, &nwalls, &walls)) return -1;
  for (PetscInt i = 0; i < D.nowned; i++) {
    PetscBool ok = PETSC_TRUE;
    for (PetscInt d = 0; d < KERGS_DIM; d++)
      ok = (PetscBool)(ok && !PetscIsInfOrNanReal(D.x[KERGS_DIM * i + d]) && !PetscIsInfOrNanReal(D.v[KERGS_DIM * i + d]));
    for (PetscInt d = 0; d < KERGS_NROT; d++)
      ok = (PetscBool)(ok && !PetscIsInfOrNanReal(D.rot[KERGS_NROT * i + d]) && !PetscIsInfOrNanReal(D.omega[KERGS_NROT * i + d]));
    if (!ok) return D.id[i];
  }
  for (PetscInt w = 0; w < nwalls; w++)
    for (PetscInt d = 0; d < KERGS_DIM; d++)
      if (PetscIsInfOrNanReal(walls[w].a[d]) || PetscIsInfOrNanReal(walls[w].v[d])) return -1; /* a wall: no grain to name */
  return PETSC_MAX_INT;
}

/* Collective, between steps: one reduction tells every rank whether a signal arrived on some rank, whether the state
   blew up (and the smallest grain id at fault; -1: a wall) and whether rank 0's clock says a checkpoint is due. */
PetscErrorCode KergsStepperPoll(KergsStepper st, KergsPoll *poll)
{
  PetscInt       v[3], g[3];
  PetscMPIInt    rank;
  PetscLogDouble now;
  const PetscInt bad = KergsStepperFirstNonFiniteGrain(st->scene);

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(st->comm, &rank));
  PetscCall(PetscTime(&now));
  v[0] = (PetscInt)Received;
  v[1] = -bad; /* max of -id: the smallest id at fault; -PETSC_MAX_INT: none */
  v[2] = rank == 0 && st->checkpoint_seconds > 0 && now - st->last_checkpoint >= st->checkpoint_seconds;
  PetscCall(MPIU_Allreduce(v, g, 3, MPIU_INT, MPI_MAX, st->comm));
  poll->signal          = (int)g[0];
  poll->blowup          = g[1] != -PETSC_MAX_INT;
  poll->blowup_grain    = -g[1];
  poll->checkpoint_time = g[2] ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Checkpoints and restarts                                                                         */

PetscErrorCode KergsStepperCheckpoint(KergsStepper st)
{
  KergsRunState  run = {st->nonconverged, st->max_violation, st->moved, st->inertial_armed};
  PetscInt       step;
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetStep(st->scene, &step, NULL, NULL));
  if (step == st->checkpoint_step) PetscFunctionReturn(0);
  PetscCall(PetscTime(&t0));
  PetscCall(KergsResultsFlush(st->results)); /* the results file holds every row the checkpoint counts */
  PetscCall(KergsCheckpointWrite(st->checkpoint_path, st->scene, st->contacts, st->partition, st->results, &run));
  PetscCall(PetscTime(&t1));
  st->checkpoint_step = step;
  st->last_checkpoint = t1;
  PetscCall(
      PetscPrintf(st->comm, "kergs: checkpoint of step %" PetscInt_FMT " in %s (%.3g s)\n", step, st->checkpoint_path, (double)(t1 - t0)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperRestore(KergsStepper st)
{
  KergsRunState run;
  PetscInt      step, nsteps;

  PetscFunctionBeginUser;
  PetscCall(KergsCheckpointRead(st->restart_path, st->scene, st->contacts, st->partition, st->results, &run));
  st->nonconverged   = run.nonconverged;
  st->max_violation  = run.max_violation;
  st->moved          = run.moved;
  st->inertial_armed = run.armed;
  PetscCall(KergsSceneGetStep(st->scene, &step, NULL, &nsteps));
  PetscCheck(nsteps >= step, st->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-steps %" PetscInt_FMT " is below the step of the checkpoint %s (%" PetscInt_FMT "): give -steps above %" PetscInt_FMT
             " to continue it",
             nsteps, st->restart_path, step, step);
  st->checkpoint_step = step; /* the checkpoint this run starts from */
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Progress lines                                                                                   */

static void FormatDuration(double s, char out[], size_t len)
{
  const long t = s > 0 && s < 1e9 ? (long)(s + 0.5) : 0;

  if (!(s >= 0 && s < 1e9))
    snprintf(out, len, "?");
  else if (t >= 3600)
    snprintf(out, len, "%ldh%02ldm%02lds", t / 3600, (t / 60) % 60, t % 60);
  else if (t >= 60)
    snprintf(out, len, "%ldm%02lds", t / 60, t % 60);
  else
    snprintf(out, len, "%.1fs", s);
}

PetscErrorCode KergsStepperProgress(KergsStepper st, PetscBool force)
{
  PetscInt       step, nsteps;
  PetscReal      time;
  PetscLogDouble now;
  PetscBool      due;
  char           eta[32];
  double         per_step, mean;

  PetscFunctionBeginUser;
  if (!st->progress_every && !st->progress_seconds && !force) PetscFunctionReturn(0);
  PetscCall(KergsSceneGetStep(st->scene, &step, &time, &nsteps));
  PetscCall(PetscTime(&now));
  /* printed by rank 0 only, so its clock alone decides: no message between ranks */
  due = (PetscBool)(force || (st->progress_every && step % st->progress_every == 0) ||
                    (st->progress_seconds && now - st->last_progress >= st->progress_seconds));
  if (!due || step == st->progress_step) PetscFunctionReturn(0);
  per_step = (now - st->last_progress) / (double)(step - st->progress_step);
  mean     = step > st->loop_start_step ? (now - st->loop_start) / (double)(step - st->loop_start_step) : 0;
  FormatDuration(mean * (double)PetscMax(nsteps - step, 0), eta, sizeof(eta));
  PetscCall(PetscPrintf(st->comm,
                        "progress: step %" PetscInt_FMT "/%" PetscInt_FMT " (%.1f%%) t %.6g contacts %" PetscInt_FMT
                        " sweeps %" PetscInt_FMT " residual %.2e max interpenetration %.2e | %.3g s/step, %s to the end\n",
                        step, nsteps, nsteps ? 100.0 * (double)step / (double)nsteps : 100.0, (double)time, st->last_contacts,
                        st->last_sweeps, (double)st->last_residual, (double)st->last_max_violation, per_step, eta));
  st->last_progress = now;
  st->progress_step = step;
  PetscFunctionReturn(0);
}
