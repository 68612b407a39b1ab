/* kergs: constants, log events and small helpers shared by every component. */
#ifndef KERGS_BASE_H
#define KERGS_BASE_H

#include <petscsys.h>

/* Spatial dimension. 3D spheres (6 DOFs per grain, 3 components per contact) are a later goal:
   every per-grain or per-contact size is derived from this constant, never a literal 2. */
#define KERGS_DIM 2
/* Rotational DOFs of a grain in KERGS_DIM dimensions (1 in 2D). */
#define KERGS_NROT (KERGS_DIM == 2 ? 1 : 3)
/* Largest number of components of a contact impulse: normal + tangential(s). */
#define KERGS_MAXCOMP KERGS_DIM

/* Log events, one per phase, so that -log_view explains the time of a step. */
PETSC_EXTERN PetscLogEvent KERGS_Detect, KERGS_Assemble, KERGS_Solve, KERGS_Sweep, KERGS_Update, KERGS_IO;
/* Communication between ranks: the ghost impulses of each sweep, the velocities gathered after each step. */
PETSC_EXTERN PetscLogEvent KERGS_Exchange;
/* The kernel projector (factorization, diagonal blocks of Z, applications), the predictor, the partition, the watch
   (src/step/watch.c: blow-ups and solver failures). */
PETSC_EXTERN PetscLogEvent  KERGS_Factor, KERGS_KernelDiag, KERGS_KernelApply, KERGS_Predict, KERGS_Partition, KERGS_Watch, KERGS_Macro;
PETSC_EXTERN PetscLogEvent  KERGS_Subdomain;     /* newton's subdomain matrices of additive Schwarz, from W's */
PETSC_EXTERN PetscLogEvent  KERGS_DeSaxce;       /* newton's De Saxce start: its QPs */
PETSC_EXTERN PetscLogEvent  KERGS_InteriorPoint; /* newton's interior-point start */
PETSC_EXTERN PetscErrorCode KergsInitializePackage(void);

/* Collective: personalised exchange of records of `size` bytes. send[] holds sendcount[q] records for rank q, grouped
   by destination in rank order. On return *(void **)recv (PetscFree) holds the records received, grouped by source
   in rank order, *nrecv their number, and recvcount[q] (may be NULL) how many came from rank q. The ranks of a run
   share one binary representation. */
PETSC_EXTERN PetscErrorCode KergsExchangeRecords(MPI_Comm, size_t size, const PetscMPIInt sendcount[], const void *send,
                                                 PetscMPIInt recvcount[], void *recv, PetscInt *nrecv);
/* Options whose number of values the user decides, read inside an options block (PetscOptionsBegin/End) so that -help
   lists them (src/base/options.c). A list of any length becomes a new array (*values, never NULL, PetscFree; names:
   PetscStrNArrayDestroy(*n, values)) and *n the number of values given, 0 when the option is absent. Reals reads
   exactly n values into v (an error names the option when another number is given; v is left unchanged when the
   option is absent; -help shows the whole default), Vector KERGS_DIM of them (a point, a velocity, a force). */
PETSC_EXTERN PetscErrorCode KergsOptionsRealList(PetscOptionItems *, const char opt[], const char text[], PetscInt *n, PetscReal **values,
                                                 PetscBool *set);
PETSC_EXTERN PetscErrorCode KergsOptionsIntList(PetscOptionItems *, const char opt[], const char text[], PetscInt *n, PetscInt **values,
                                                PetscBool *set);
PETSC_EXTERN PetscErrorCode KergsOptionsStringList(PetscOptionItems *, const char opt[], const char text[], PetscInt *n, char ***values,
                                                   PetscBool *set);
PETSC_EXTERN PetscErrorCode KergsOptionsReals(PetscOptionItems *, const char opt[], const char text[], PetscInt n, PetscReal v[],
                                              PetscBool *set);
PETSC_EXTERN PetscErrorCode KergsOptionsVector(PetscOptionItems *, const char opt[], const char text[], PetscReal v[], PetscBool *set);
/* Counts and indices are PetscInt, 32-bit in this build: PETSc's options parser wraps a larger value silently
   (-steps 10000000000 becomes 1410065408). Call after the option was read: every comma-separated number given to
   option `name` (under prefix, may be NULL) must fit in PetscInt, otherwise an error on comm names the option and the
   largest value allowed. Options that are not given, and values that are not numbers, pass. */
PETSC_EXTERN PetscErrorCode KergsOptionsCheckInt(MPI_Comm, const char prefix[], const char name[]);
/* PetscOptionsInt inside an options block, with the option's value checked for overflow first (KergsOptionsCheckInt):
   integer options are read through this, so that a wrapped count is never used. */
PETSC_EXTERN PetscErrorCode KergsOptionsInt(PetscOptionItems *, const char opt[], const char text[], const char man[], PetscInt current,
                                            PetscInt *value, PetscBool *set);
/* PETSc refuses an unknown truth value with "Unknown logical value: maybe", naming no option. Call before reading
   option `name` (under prefix, may be NULL) as a bool: a value other than true, false, yes, no, on, off, 1 or 0 (any
   case) is an error on comm naming the option and the values accepted; absent or given alone (true), it passes. */
PETSC_EXTERN PetscErrorCode KergsOptionsCheckBool(MPI_Comm, const char prefix[], const char name[]);
/* PetscOptionsBool inside an options block, the value checked first (KergsOptionsCheckBool). */
PETSC_EXTERN PetscErrorCode KergsOptionsBool(PetscOptionItems *, const char opt[], const char text[], const char man[], PetscBool current,
                                             PetscBool *value, PetscBool *set);
/* As PetscObjectViewFromOptions for kergs's objects: when option (under prefix, may be NULL) is given, with PETSc's
   viewer syntax (-x_view, -x_view ::ascii_info_detail, -x_view ascii:FILE), view obj there with view(obj, viewer).
   Collective on comm. */
PETSC_EXTERN PetscErrorCode KergsViewFromOptions(MPI_Comm, const char prefix[], const char option[],
                                                 PetscErrorCode (*view)(void *, PetscViewer), void *obj);
/* Collective, before the options are read: an option of the database given without a value, which the help of the
   program's readers lists as taking one, is an error naming it (PETSc's readers would take it as not given). read_all
   reads every option the program reads, as with -help; it runs, with -help set, on a copy of the database, only when
   some option has no value. Flags, viewers (whose value is optional), PETSc's own options and those of PETSc objects
   pass. */
PETSC_EXTERN PetscErrorCode KergsOptionsCheckValues(MPI_Comm, PetscErrorCode (*read_all)(MPI_Comm, void *), void *ctx);
/* The options of PetscOptionsGetAll's text ("-name value words -flag -name2 value"), in order: visit(name, value, ctx),
   the value's words joined by one space ("" for a flag). A token is a name when it is '-' then a letter (a negative
   number such as -0.05 is a value). Reads nothing from the database: no option is marked as read. */
typedef PetscErrorCode (*KergsOptionVisitor)(const char name[], const char value[], void *ctx);
PETSC_EXTERN PetscErrorCode KergsOptionsTextWalk(const char text[], KergsOptionVisitor visit, void *ctx);
/* The largest number of disks this build can hold: KERGS_DIM values per disk must be indexable by PetscInt. */
#define KERGS_MAX_DISKS (PETSC_MAX_INT / KERGS_DIM)
/* Provenance of a run, as the output files record it (docs/results.md): the version of the sources, captured at build
   time (git describe; "unknown" outside a git checkout), the date (UTC, ISO 8601), the number of ranks and the whole
   options database as text. Collective: the date and the options are rank 0's, the same on every rank. */
typedef struct {
  const char *version;
  char        date[32];
  PetscMPIInt ranks;
  char       *options; /* PetscOptionsGetAll's text; freed by KergsProvenanceDestroy */
} KergsProvenance;
PETSC_EXTERN PetscErrorCode KergsProvenanceGet(MPI_Comm, KergsProvenance *);
/* Collective: the options of the run as they stand now (rank 0's), reported by every later KergsProvenanceGet instead of
   the database's current state, into which components add their own settings as they set up (the stepper calls it
   once all options are known, before the run). */
PETSC_EXTERN PetscErrorCode KergsProvenanceSetOptions(MPI_Comm);
PETSC_EXTERN PetscErrorCode KergsProvenanceDestroy(KergsProvenance *);
PETSC_EXTERN const char    *KergsGetVersion(void);
/* Let the C library return freed blocks to the system (glibc: large blocks mapped on their own, heap tops trimmed),
   undoing a process-wide setting of a library PETSc loads; no-op elsewhere. Call it once, first thing in main. */
PETSC_EXTERN void KergsReturnFreedMemory(void);
/* PETSc's error handler, which reports a failed allocation by the function's name alone ("DisksFromLattice"), with a
   first line that says it was out of memory, where, and what to change. Push after PetscInitialize (main). */
PETSC_EXTERN PetscErrorCode KergsPushErrorHandler(void);
/* An error raised while a file is open on several ranks is held until the file is closed, then raised again:
     PetscCall(KergsErrorsHoldBegin()); ierr = Load(viewer); PetscCall(KergsErrorsHoldEnd());
     PetscCall(PetscViewerDestroy(&viewer)); PetscCall(KergsErrorsRaiseHeld(comm, ierr, "Sample file", path));
   Without it, PETSc's handler makes every rank but the first sleep 10 s after printing nothing (so that the first rank
   prints and aborts the run), while the first rank waits for them in the file's collective close: a refusal took 10 s
   to exit on 2 ranks. Between Begin and End errors return without a word and the first is kept; RaiseHeld
   (collective) raises it again with its message and the function, file and line where it arose (prefixed with role and
   path when the message does not name the file, as HDF5's own failures on a corrupt file do), once on comm when every
   rank holds one. Holding suits the errors every rank meets at the same point (a file's content, read by all); one
   rank's error leaves it closing the file while the others read on, so a failed allocation, one rank's by nature, is
   not held: it prints that it was out of memory and aborts the run. */
PETSC_EXTERN PetscErrorCode KergsErrorsHoldBegin(void);
PETSC_EXTERN PetscErrorCode KergsErrorsHoldEnd(void);
PETSC_EXTERN PetscErrorCode KergsErrorsRaiseHeld(MPI_Comm, PetscErrorCode, const char[], const char[]);
/* The rank owning global index i when rank q owns [ranges[q], ranges[q+1]) (size + 1 entries, non-decreasing; an
   empty rank is skipped: a later rank starts at the same index). */
static inline PetscMPIInt KergsRangeOwner(const PetscInt ranges[], PetscMPIInt size, PetscInt i)
{
  PetscMPIInt lo = 0, hi = size - 1;

  while (lo < hi) { /* the last rank q with ranges[q] <= i */
    PetscMPIInt mid = (lo + hi + 1) / 2;
    if (ranges[mid] <= i)
      lo = mid;
    else
      hi = mid - 1;
  }
  return lo;
}

#endif
