/* kergs results, private: the results writer's fields, for src/io/results.c only; other components go through
   kergs/results.h. */
#ifndef KERGS_RESULTSIMPL_H
#define KERGS_RESULTSIMPL_H

#include <kergs/results.h>
#include <kergs/xdmf.h>

#define KERGS_RESULTS_MAXTEXTS 16

struct _p_KergsResults {
  MPI_Comm    comm;
  char        path[PETSC_MAX_PATH_LEN], tmppath[PETSC_MAX_PATH_LEN];
  PetscViewer viewer;
  PetscInt    snapshot_every; /* -output_every: steps between snapshots (0: first and last only) */
  PetscInt    nsnapshots;
  /* statistics: rows [0, nrows) are complete, row nrows is being recorded. Rows [0, nflushed) are in the file; memory
     holds rows [row0, nrows], row r at index r - row0 of statvalues[j] (capacity nalloc): after a flush only the last
     complete row stays (row0 = nrows - 1), and without a file (-output_none) every row (row0 = 0). */
  PetscInt       nstats, nrows, nalloc, row0, nflushed;
  char           statname[KERGS_RESULTS_MAXSTATS][64];
  PetscReal     *statvalues[KERGS_RESULTS_MAXSTATS];
  PetscInt       flush_every;   /* -output_flush_every: rows between flushes */
  PetscReal      flush_seconds; /* -output_flush_seconds: seconds between flushes (rank 0's clock) */
  PetscLogDouble last_flush;    /* wall clock of the last flush (rank 0) */
  PetscBool      enabled;
  char           scenename[PETSC_MAX_PATH_LEN]; /* names the default output path results/<scenename>.h5 */
  PetscInt       last_snapshot_step;            /* step of the latest snapshot (-1: none yet) */
  PetscInt       ntexts;                        /* texts of the run (KergsResultsRecordText), string attributes of /stats */
  char           textname[KERGS_RESULTS_MAXTEXTS][64], textvalue[KERGS_RESULTS_MAXTEXTS][512];
  char           textstat[KERGS_RESULTS_MAXTEXTS][64]; /* the statistic whose dataset holds the text (empty: /stats itself) */
  char           end[256];                             /* how the run ended (KergsResultsSetEnd), the root attribute `end` at close */
  /* restart (KergsResultsSetContinue): the checkpointed run's results file and its state at the checkpoint */
  char              source[PETSC_MAX_PATH_LEN];
  KergsResultsState source_state;
  PetscInt          source_step;
  PetscBool         continued; /* the open file continues the source (otherwise it began at the restart) */
  /* XDMF file beside the results (-output_xdmf, src/io/xdmf.c): the snapshots' attributes, written by rank 0 */
  PetscBool          xdmf;
  char               xdmfpath[PETSC_MAX_PATH_LEN];
  KergsXdmfSnapshot *snaps; /* [0, nsnapshots), capacity nsnapalloc */
  PetscInt           nsnapalloc;
  PetscInt           xdmf_written; /* snapshots listed in the XDMF file on disk */
  PetscLogDouble     last_xdmf;    /* wall clock of its last rewrite (rank 0) */
  PetscLogDouble     xdmf_cost;    /* seconds that rewrite took */
};

#endif
