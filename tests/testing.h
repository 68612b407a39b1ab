/* Helpers shared by the whole-engine test programs: a check line that counts failures, a stepper configured
   only by given options, and a recorded statistic by name. */
#ifndef KERGS_TESTING_H
#define KERGS_TESTING_H

#include "internals.h"

static PetscInt nfail = 0;

/* Print one line per check ("ok" or "FAIL", with what was got and wanted) and count the failures. */
static inline PetscErrorCode Check(PetscBool ok, const char *what, PetscReal got, PetscReal want)
{
  PetscFunctionBeginUser;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s %-72s got %.10g want %.10g\n", ok ? "ok  " : "FAIL", what, (double)got, (double)want));
  if (!ok) nfail++;
  PetscFunctionReturn(0);
}

/* A fresh stepper on comm configured only by the given options (the options database is reset). */
static inline PetscErrorCode MakeStepperOn(MPI_Comm comm, const char *opts, KergsStepper *st)
{
  PetscFunctionBeginUser;
  PetscCall(PetscOptionsClear(NULL));
  PetscCall(PetscOptionsInsertString(NULL, opts));
  PetscCall(PetscOptionsInsertString(NULL, "-output_none -quiet"));
  PetscCall(KergsStepperCreate(comm, st));
  PetscCall(KergsStepperSetFromOptions(*st));
  PetscFunctionReturn(0);
}

static inline PetscErrorCode MakeStepper(const char *opts, KergsStepper *st)
{
  return MakeStepperOn(PETSC_COMM_WORLD, opts, st);
}

/* The statistic `name` recorded for step row `row` (-1: the last step). */
static inline PetscErrorCode StatAt(KergsResults res, const char *name, PetscInt row, PetscReal *value)
{
  PetscFunctionBeginUser;
  *value = PETSC_MAX_REAL;
  if (row < 0) row = res->nrows - 1;
  for (PetscInt s = 0; s < res->nstats; s++) {
    PetscBool same;
    PetscCall(PetscStrcmp(res->statname[s], name, &same));
    if (same && row >= 0 && row < res->nrows) *value = res->statvalues[s][row];
  }
  PetscCheck(*value != PETSC_MAX_REAL, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "No statistic %s recorded for row %" PetscInt_FMT, name, row);
  PetscFunctionReturn(0);
}

/* A per-disk field of the owned disks (bs values per disk) gathered over the ranks into grain-id order on every
   rank (out: bs * ndisks values; the grain ids must be 0 .. ndisks-1). Independent of the partition, so that runs
   on different numbers of ranks compare grain by grain. */
static inline PetscErrorCode GatherById(KergsScene sc, const PetscReal *owned, PetscInt bs, PetscReal *out)
{
  PetscReal *all;
  PetscInt  *ids;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(bs * sc->ndisks + 1, &all, sc->ndisks + 1, &ids));
  PetscCall(KergsSceneAllGatherReal(sc, owned, bs, all));
  PetscCall(KergsSceneAllGatherInt(sc, sc->id, 1, ids));
  for (PetscInt g = 0; g < sc->ndisks; g++) {
    PetscCheck(ids[g] >= 0 && ids[g] < sc->ndisks, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "GatherById: grain id %" PetscInt_FMT " outside [0, %" PetscInt_FMT ")", ids[g], sc->ndisks);
    for (PetscInt d = 0; d < bs; d++) out[bs * ids[g] + d] = all[bs * g + d];
  }
  PetscCall(PetscFree2(all, ids));
  PetscFunctionReturn(0);
}

/* The closing line and the exit code of a test program. */
static inline int Finish(void)
{
  PetscCallAbort(PETSC_COMM_WORLD, PetscPrintf(PETSC_COMM_WORLD, "%s: %" PetscInt_FMT " failed checks\n", nfail ? "FAILED" : "PASSED", nfail));
  return nfail ? 1 : 0;
}

#endif
