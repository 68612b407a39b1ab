/* kergs files: what the output files of the io component share (src/io/files.c, docs/results.md "Atomic writing",
   docs/running.md).

   Every output is written under <path>.tmp and renamed to <path> once complete (KergsFileCommit). The paths of a run
   are checked before any work (KergsFileCheckPaths), free space before each large write (KergsFileCheckSpace), and a
   failed write removes its partial .tmp and says whether the disk was full (KergsFileWriteFailed: HDF5 itself reports
   only "file write failed", never ENOSPC). Collective functions do the file system work on rank 0 and give every
   rank the same error. */
#ifndef KERGS_FILES_H
#define KERGS_FILES_H

#include <kergs/scene.h>
#include <petscviewer.h>

/* The directories leading to path, created like mkdir -p of its dirname; then path and path.tmp must be regular files
   or not exist (KergsFileReplaceable). Collective. */
PETSC_EXTERN PetscErrorCode KergsFileMakeParentDir(MPI_Comm, const char path[]);
/* Waits for every rank (after the file was closed everywhere), then renames tmp to path, unless path is no longer
   replaceable (KergsFileReplaceable: the .tmp is kept). Collective. */
PETSC_EXTERN PetscErrorCode KergsFileCommit(MPI_Comm, const char tmp[], const char path[]);
/* Whether renaming a file to path is safe: path does not exist or is a regular file (links followed). Otherwise
   (a device, a directory, a pipe, a socket) msg says what path is. Not collective; plain C (no PETSc error). */
PETSC_EXTERN PetscBool KergsFileReplaceable(const char path[], char msg[], size_t len);
/* Whether path exists (rank 0's view, collective). */
PETSC_EXTERN PetscErrorCode KergsFileExists(MPI_Comm, const char path[], PetscBool *);
/* Copies src to dst byte for byte (rank 0; dst is replaced). Collective. */
PETSC_EXTERN PetscErrorCode KergsFileCopy(MPI_Comm, const char src[], const char dst[]);
/* Before writing about `bytes` more into tmp (the temporary of path): when the file system of path has less room (statvfs
   on rank 0), removes tmp (NULL: nothing to remove) and raises "No space left on device" naming path, on every rank.
   `what` names the write ("snapshot of step 12") in the message. Collective. */
PETSC_EXTERN PetscErrorCode KergsFileCheckSpace(MPI_Comm, const char path[], const char tmp[], const char what[], PetscReal bytes);
/* After a write of tmp (the temporary of path) failed on this rank: removes tmp and returns an error (PETSC_COMM_SELF)
   that says "No space left on device" when the file system of path is full, or else that the write failed. Not
   collective: the other ranks may be inside the same collective write, so the run must end (the error goes up to
   main). */
PETSC_EXTERN PetscErrorCode KergsFileWriteFailed(const char path[], const char tmp[], const char what[]);

/* A file of the run and the option that names it (KergsFileCheckPaths). */
typedef struct {
  const char *option; /* "-output" */
  const char *path;   /* empty or NULL: not used in this run */
} KergsFileRole;
/* Before any work: every output must be writable (its directory exists or can be created, and files can be created
   in it), must be a regular file or not exist (nor its .tmp: no device, directory, pipe), and must differ from every input and every other
   output, the outputs' .tmp files included; paths are compared after resolving links (realpath of the parent directory plus the base name,
   directories still to be created normalised: newdir/../a is ./a; and for an existing input also the realpath of the file itself). An input
   that is also allowed as an output of the same run is listed in `same` pairs (output option, input option) (e.g. -checkpoint_path may be
   the -restart file: read whole before the run starts, replaced atomically). Errors name the options and paths.
   Collective. */
PETSC_EXTERN PetscErrorCode KergsFileCheckPaths(MPI_Comm, PetscInt nout, const KergsFileRole outputs[], PetscInt nin,
                                                const KergsFileRole inputs[], PetscInt nsame, const char *const same[][2]);

/* The files that PETSc viewers named by option values write: "type:file[:format[:mode]]" of the ASCII, binary, HDF5,
   VTK and MATLAB viewers, and -log_view's ":file" (stdout and stderr are streams, not files), read from the options
   database; each file once, with the first option that names it (viewers of one file share it), at most
   KERGS_MAX_VIEWER_FILES. A viewer opens its file (an ASCII one truncates it) when its option is read, so these are
   checked against the inputs before anything reads the options. */
#define KERGS_MAX_VIEWER_FILES 16
typedef struct {
  PetscInt n;
  char     option[KERGS_MAX_VIEWER_FILES][64], path[KERGS_MAX_VIEWER_FILES][PETSC_MAX_PATH_LEN];
} KergsViewerFiles;
PETSC_EXTERN PetscErrorCode KergsFileViewerFiles(KergsViewerFiles *);

/* Every options file of the command line (-options_file FILE) and those they include, in PETSc's order (visit, when
   not NULL, is called with each path as written). A file that includes itself, directly or through others, makes PETSc
   recurse until the stack overflows: then msg names the chain and the function returns 1, else 0. Plain C, before
   PetscInitialize (main) and after. */
typedef void (*KergsOptionsFileVisitor)(const char path[], void *ctx);
PETSC_EXTERN int KergsOptionsFilesWalk(int argc, char **argv, KergsOptionsFileVisitor visit, void *ctx, char msg[], size_t len);

/* Open MPI's MPI-IO (ompio) aborts with glibc's "buffer overflow detected" on file paths of 241 characters or more, in
   its sharedfp/lockedfile component (which HDF5 never uses). Unless the user set OMPI_MCA_sharedfp, exclude that
   component (setenv, before MPI_Init: call it first thing in main). */
PETSC_EXTERN void KergsFileAvoidLongPathAbort(void);

/* Shared by the HDF5 writers (results, samples, checkpoints): one dataset from the nlocal blocks of bs values this rank
   holds, stacked in rank order; integers are stored as reals (exact up to 2^53). Collective. */
PETSC_EXTERN PetscErrorCode KergsViewBlocks(PetscViewer, MPI_Comm, const char name[], PetscInt nlocal, PetscInt bs,
                                            const PetscReal *values);
PETSC_EXTERN PetscErrorCode KergsViewIntegers(PetscViewer, MPI_Comm, const char name[], PetscInt nlocal, const PetscInt *values);
/* Their readers. Dataset `name` of the viewer's current group (`group` and the file's `path` name it in errors), which
   must hold nglobal blocks of bs values: *nlocal of them on this rank (the ranks' parts in rank order; PETSC_DECIDE: an
   even split, *nlocal set), or all of them on every rank, into a new array (PetscFree). Collective. */
PETSC_EXTERN PetscErrorCode KergsLoadBlocks(PetscViewer, MPI_Comm, const char path[], const char group[], const char name[],
                                            PetscInt nglobal, PetscInt bs, PetscInt *nlocal, PetscReal **local);
PETSC_EXTERN PetscErrorCode KergsLoadAllBlocks(PetscViewer, MPI_Comm, const char path[], const char group[], const char name[],
                                               PetscInt nglobal, PetscInt bs, PetscReal **all);

#endif
