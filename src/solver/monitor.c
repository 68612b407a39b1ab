/* kergs solver: monitors of the iterations inside a step, as KSPMonitorSet does for a KSP. The types report each
   iteration (KergsSolverMonitor); -solver_monitor [ascii:FILE] prints one line per iteration. The call of the last
   iteration is held back until the solve's exit (KergsSolverMonitorFlush), so that it carries the natural residual
   recorded for the step: the line count equals the step's `iterations`, and its last residual the step's `residual`. */
#include <kergs/private/solverimpl.h>

PetscErrorCode KergsSolverMonitorSet(KergsSolver s, KergsSolverMonitorFn fn, void *ctx, PetscErrorCode (*destroy)(void **))
{
  PetscFunctionBeginUser;
  PetscCheck(s->nmonitors < KERGS_SOLVER_MAXMONITORS, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "At most %d solver monitors",
             KERGS_SOLVER_MAXMONITORS);
  s->monitor[s->nmonitors]        = fn;
  s->monitorctx[s->nmonitors]     = ctx;
  s->monitordestroy[s->nmonitors] = destroy;
  s->nmonitors++;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverMonitorCancel(KergsSolver s)
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < s->nmonitors; i++)
    if (s->monitordestroy[i]) PetscCall((*s->monitordestroy[i])(&s->monitorctx[i]));
  s->nmonitors       = 0;
  s->monitor_options = PETSC_FALSE;
  s->held            = PETSC_FALSE;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverSetStepNumber(KergsSolver s, PetscInt step)
{
  PetscFunctionBeginUser;
  s->step = step;
  PetscFunctionReturn(0);
}

static PetscErrorCode MonitorCall(KergsSolver s, PetscInt it, PetscReal criterion, PetscReal residual, PetscReal seconds)
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < s->nmonitors; i++) PetscCall((*s->monitor[i])(s, s->step, it, criterion, residual, seconds, s->monitorctx[i]));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverMonitor(KergsSolver s, PetscInt it, PetscReal criterion, PetscReal residual)
{
  PetscLogDouble now;

  PetscFunctionBeginUser;
  if (!s->nmonitors) PetscFunctionReturn(0);
  PetscCall(PetscTime(&now));
  if (s->held) PetscCall(MonitorCall(s, s->held_it, s->held_criterion, s->held_residual, s->held_seconds));
  s->held           = PETSC_TRUE;
  s->held_it        = it;
  s->held_criterion = criterion;
  s->held_residual  = residual;
  s->held_seconds   = (PetscReal)(now - s->solve_start);
  PetscFunctionReturn(0);
}

/* At the solve's exit: the held-back last iteration, with the natural residual recomputed from r at exit (the r the
   step keeps, after the last iteration). */
PetscErrorCode KergsSolverMonitorFlush(KergsSolver s, PetscReal residual)
{
  PetscFunctionBeginUser;
  if (!s->held) PetscFunctionReturn(0);
  s->held = PETSC_FALSE;
  PetscCall(MonitorCall(s, s->held_it, s->held_criterion, residual, s->held_seconds));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverMonitorDefault(KergsSolver s, PetscInt step, PetscInt it, PetscReal criterion, PetscReal residual,
                                         PetscReal seconds, void *ctx)
{
  PetscViewerAndFormat *vf = (PetscViewerAndFormat *)ctx;
  char                  res[32];

  PetscFunctionBeginUser;
  (void)s;
  if (PetscIsNanReal(residual))
    PetscCall(PetscStrncpy(res, "-", sizeof(res))); /* not computed by the type at this iteration */
  else
    PetscCall(PetscSNPrintf(res, sizeof(res), "%.10e", (double)residual));
  PetscCall(PetscViewerASCIIPrintf(vf->viewer,
                                   "step %" PetscInt_FMT " iteration %" PetscInt_FMT " criterion %.10e residual %s seconds %.6e\n", step,
                                   it, (double)criterion, res, (double)seconds));
  PetscFunctionReturn(0);
}

static PetscErrorCode MonitorDestroyDefault(void **ctx)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerAndFormatDestroy((PetscViewerAndFormat **)ctx));
  PetscFunctionReturn(0);
}

/* -solver_monitor [ascii[:FILE]], inside the solver's options block */
PetscErrorCode KergsSolverMonitorSetFromOptions(PetscOptionItems *PetscOptionsObject, KergsSolver s)
{
  PetscViewer       viewer;
  PetscViewerFormat format;
  PetscBool         set, ascii;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsViewer("-solver_monitor",
                               "One line per iteration of a step (sweep or Newton step): step, iteration, criterion, natural residual, "
                               "seconds since the solve started",
                               "KergsSolverMonitorSet", &viewer, &format, &set));
  if (!set || s->monitor_options) {
    if (set) PetscCall(PetscViewerDestroy(&viewer));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  PetscCheck(ascii, s->comm, PETSC_ERR_SUP, "-solver_monitor writes text: give no viewer, ascii or ascii:FILE");
  {
    PetscViewerAndFormat *vf;
    PetscCall(PetscViewerAndFormatCreate(viewer, format, &vf));
    PetscCall(PetscViewerDestroy(&viewer)); /* vf holds its own reference */
    PetscCall(KergsSolverMonitorSet(s, KergsSolverMonitorDefault, vf, MonitorDestroyDefault));
  }
  s->monitor_options = PETSC_TRUE;
  PetscFunctionReturn(0);
}
