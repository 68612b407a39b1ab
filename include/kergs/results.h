/* kergs results: one HDF5 file per run, written through PetscViewerHDF5 under a temporary name and
   renamed when complete (atomic). Layout in docs/results.md:
     /stats/<name>                 one 1-D dataset per statistic, one entry per step (chunked, extendible)
     /snapshots/<k>/...            grain ids, positions, velocities, radii; contact list
   and, beside it, an XDMF file that describes the snapshots for ParaView (-output_xdmf, kergs/xdmf.h).
   Statistics are recorded by name each step (KergsResultsRecord), so components add their own.
   A statistic first recorded after some rows were completed gets NaN in those earlier rows, and a
   statistic not recorded in a step gets NaN in that row.

   Nothing waits for the end of the run: the rows are appended to /stats and the file is flushed to disk every
   -output_flush_every rows or -output_flush_seconds seconds, and after every snapshot, so that <path>.tmp is a
   readable HDF5 file holding every flushed row and snapshot if the run is killed (docs/results.md, "Atomic writing").

   Use: Create, (SetSceneName), SetFromOptions, (SetContinue), Open; per step Record ... EndStep and, when
   KergsResultsSnapshotDue says so, Snapshot; (SetEnd); Close at the end; Destroy. With -output_none every call
   is a no-op. */
#ifndef KERGS_RESULTS_H
#define KERGS_RESULTS_H

#include <kergs/detect.h>
#include <kergs/files.h>

#define KERGS_RESULTS_MAXSTATS 128

typedef struct _p_KergsResults *KergsResults;

PETSC_EXTERN PetscErrorCode KergsResultsCreate(MPI_Comm, KergsResults *);
/* Name used for the default path results/<name>.h5 when -output is not given (call before Open;
   without it the default is results/kergs.h5). */
PETSC_EXTERN PetscErrorCode KergsResultsSetSceneName(KergsResults, const char name[]);
/* -output, -output_every, -output_none, -output_flush_every, -output_flush_seconds */
PETSC_EXTERN PetscErrorCode KergsResultsSetFromOptions(KergsResults);
/* Creates <path>.tmp with the root attributes (format, provenance: KergsProvenance), or continues a file (SetContinue). */
PETSC_EXTERN PetscErrorCode KergsResultsOpen(KergsResults);
/* Record one statistic of the current step (same call on every rank, values already reduced). */
PETSC_EXTERN PetscErrorCode KergsResultsRecord(KergsResults, const char name[], PetscReal value);
/* Complete the current row; flushes when -output_flush_every rows or -output_flush_seconds have passed. Collective. */
PETSC_EXTERN PetscErrorCode KergsResultsEndStep(KergsResults);
/* Write the completed rows not yet in the file, the attributes that change (nrows, nsnapshots, texts), and flush the
   file to disk (H5Fflush). Collective; no-op without an open file. */
PETSC_EXTERN PetscErrorCode KergsResultsFlush(KergsResults);
/* Record a text of the run (a type name, ...) as a string attribute of /stats; the last value given is kept. */
PETSC_EXTERN PetscErrorCode KergsResultsRecordText(KergsResults, const char name[], const char value[]);
/* The same, as a string attribute of the dataset of statistic stat (recorded by then), e.g. the names of its values */
PETSC_EXTERN PetscErrorCode KergsResultsRecordStatisticText(KergsResults, const char stat[], const char name[], const char value[]);
/* The statistic `name` of step row `row` (-1: the last completed row), as recorded so far; *found tells whether it was
   recorded (NaN for a row where it was not). Rows already flushed to the file are no longer held in memory, except the
   last completed one; with -output_none every row is. */
PETSC_EXTERN PetscErrorCode KergsResultsGetStatistic(KergsResults, const char name[], PetscInt row, PetscReal *value, PetscBool *found);
/* Rows completed so far */
PETSC_EXTERN PetscErrorCode KergsResultsGetNumRows(KergsResults, PetscInt *);
/* The results file's path, and whether results are written at all (-output_none) */
PETSC_EXTERN PetscErrorCode KergsResultsGetPath(KergsResults, const char **path, PetscBool *enabled);
/* The XDMF file written beside the results file (-output_xdmf, include/kergs/xdmf.h); empty when none is written. */
PETSC_EXTERN PetscErrorCode KergsResultsGetXdmfPath(KergsResults, const char **path);
/* Whether the snapshot policy asks for a snapshot at this step: the first snapshot of the run (none
   written yet), the last step (last = PETSC_TRUE), and with -output_every N > 0 every step that is a
   multiple of N. Always PETSC_FALSE with -output_none. */
PETSC_EXTERN PetscErrorCode KergsResultsSnapshotDue(KergsResults, PetscInt step, PetscBool last, PetscBool *due);
/* Write /snapshots/<k> for the scene's current step (collective), then flush. A second call for the same step is
   ignored, so a final unconditional call after the loop does not duplicate the last snapshot. */
PETSC_EXTERN PetscErrorCode KergsResultsSnapshot(KergsResults, KergsScene, KergsContacts);
/* How the run ended ("done", "stopped by SIGTERM", ...): the root attribute `end`, written at Close. */
PETSC_EXTERN PetscErrorCode KergsResultsSetEnd(KergsResults, const char end[]);
/* Write the last rows, mark the file complete, close and rename the temporary file to its final name. */
PETSC_EXTERN PetscErrorCode KergsResultsClose(KergsResults);
/* A run that fails before its first step (bad input found then, e.g. overlapping grains): the file opened by this run
   is closed and removed, <path>.tmp and its XDMF file, so that no output is left. A continued file (a restart) is kept.
   Collective. */
PETSC_EXTERN PetscErrorCode KergsResultsDiscard(KergsResults);
PETSC_EXTERN PetscErrorCode KergsResultsDestroy(KergsResults *);

/* What a checkpoint keeps of the writer, so that a restarted run continues the same file as if never stopped. */
typedef struct {
  PetscInt nrows;              /* rows completed */
  PetscInt nsnapshots;         /* snapshots written */
  PetscInt last_snapshot_step; /* step of the latest snapshot (-1: none) */
} KergsResultsState;
PETSC_EXTERN PetscErrorCode KergsResultsGetState(KergsResults, KergsResultsState *);
/* Before Open, for a run restarted from a checkpoint of step `step`: continue source, the results file of the
   checkpointed run (its final name or its .tmp, whichever holds the checkpoint's rows: the .tmp is tried first).
   Open copies it to <path>.tmp (or continues it in place when it is that .tmp), keeps its first state->nrows rows and
   state->nsnapshots snapshots (what a later part of the checkpointed run added is dropped), checks that its last row
   is step `step`, and appends from there. When neither file exists, the file begins at the restart (a note says so);
   when one exists but does not hold the checkpoint's rows, Open fails naming it. */
PETSC_EXTERN PetscErrorCode KergsResultsSetContinue(KergsResults, const char source[], const KergsResultsState *state, PetscInt step);

#endif
