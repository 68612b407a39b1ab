/* kergs: log events of the phases of a step, registered once, the personalised exchange of records, and the
   allocator's policy. */
#include <kergs/base.h>
#include <petscviewer.h>
#include <kergs/version.h> /* generated at build time (cmake/version.cmake) */
#include <string.h>
#include <time.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

PetscLogEvent KERGS_Detect, KERGS_Assemble, KERGS_Solve, KERGS_Sweep, KERGS_Update, KERGS_IO, KERGS_Exchange;
PetscLogEvent KERGS_Factor, KERGS_KernelDiag, KERGS_KernelApply, KERGS_Predict, KERGS_Partition, KERGS_Watch, KERGS_Macro;
PetscLogEvent KERGS_Subdomain;
PetscLogEvent KERGS_DeSaxce;
PetscLogEvent KERGS_InteriorPoint;

static PetscBool PackageInitialized = PETSC_FALSE;
static char     *RunOptions         = NULL; /* KergsProvenanceSetOptions: the options of the run as given (rank 0) */

/* At PetscFinalize: PETSc may be initialized again in the same process (the tests do), and the events then need
   registering again. */
static PetscErrorCode FinalizePackage(void)
{
  PetscFunctionBeginUser;
  PackageInitialized = PETSC_FALSE;
  PetscCall(PetscFree(RunOptions));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsInitializePackage(void)
{
  PetscClassId classid;

  PetscFunctionBeginUser;
  if (PackageInitialized) PetscFunctionReturn(0);
  PackageInitialized = PETSC_TRUE;
  PetscCall(PetscRegisterFinalize(FinalizePackage));
  PetscCall(PetscClassIdRegister("kergs", &classid));
  PetscCall(PetscLogEventRegister("KergsDetect", classid, &KERGS_Detect));
  PetscCall(PetscLogEventRegister("KergsAssemble", classid, &KERGS_Assemble));
  PetscCall(PetscLogEventRegister("KergsSolve", classid, &KERGS_Solve));
  PetscCall(PetscLogEventRegister("KergsSweep", classid, &KERGS_Sweep));
  PetscCall(PetscLogEventRegister("KergsUpdate", classid, &KERGS_Update));
  PetscCall(PetscLogEventRegister("KergsIO", classid, &KERGS_IO));
  PetscCall(PetscLogEventRegister("KergsExchange", classid, &KERGS_Exchange));
  PetscCall(PetscLogEventRegister("KergsFactor", classid, &KERGS_Factor));
  PetscCall(PetscLogEventRegister("KergsKernelDiag", classid, &KERGS_KernelDiag));
  PetscCall(PetscLogEventRegister("KergsKernelApply", classid, &KERGS_KernelApply));
  PetscCall(PetscLogEventRegister("KergsPredict", classid, &KERGS_Predict));
  PetscCall(PetscLogEventRegister("KergsPartition", classid, &KERGS_Partition));
  PetscCall(PetscLogEventRegister("KergsWatch", classid, &KERGS_Watch));
  PetscCall(PetscLogEventRegister("KergsMacro", classid, &KERGS_Macro));
  PetscCall(PetscLogEventRegister("KergsSubdomain", classid, &KERGS_Subdomain));
  PetscCall(PetscLogEventRegister("KergsDeSaxce", classid, &KERGS_DeSaxce));
  PetscCall(PetscLogEventRegister("KergsInteriorPt", classid, &KERGS_InteriorPoint));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsExchangeRecords(MPI_Comm comm, size_t size, const PetscMPIInt sendcount[], const void *send, PetscMPIInt recvcount[],
                                    void *recv, PetscInt *nrecv)
{
  PetscMPIInt  nranks, *sdispl, *rcount, *rdispl;
  MPI_Datatype record;
  void       **out = (void **)recv;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &nranks));
  PetscCall(PetscMalloc3(nranks, &sdispl, nranks, &rcount, nranks, &rdispl));
  PetscCallMPI(MPI_Alltoall((void *)sendcount, 1, MPI_INT, rcount, 1, MPI_INT, comm));
  *nrecv = 0;
  for (PetscMPIInt q = 0; q < nranks; q++) {
    sdispl[q] = q ? sdispl[q - 1] + sendcount[q - 1] : 0;
    rdispl[q] = (PetscMPIInt)*nrecv;
    *nrecv += rcount[q];
  }
  PetscCall(PetscMalloc(size * (size_t)(*nrecv + 1), out));
  PetscCallMPI(MPI_Type_contiguous((PetscMPIInt)size, MPI_BYTE, &record));
  PetscCallMPI(MPI_Type_commit(&record));
  PetscCallMPI(MPI_Alltoallv((void *)send, (PetscMPIInt *)sendcount, sdispl, record, *out, rcount, rdispl, record, comm));
  PetscCallMPI(MPI_Type_free(&record));
  if (recvcount) PetscCall(PetscArraycpy(recvcount, rcount, nranks));
  PetscCall(PetscFree3(sdispl, rcount, rdispl));
  PetscFunctionReturn(0);
}

/* PETSc 3.18's allocator (PetscMallocAlign, PetscReallocAlign) raises its failure with the calling function's name as
   the whole message (and an error code of its own, not always PETSC_ERR_MEM): recognised by the function that raised
   it. */
static PetscBool AllocationFailed(const char *fun, PetscErrorCode n)
{
  return (PetscBool)(n == PETSC_ERR_MEM || (fun && (!strcmp(fun, "PetscMallocAlign") || !strcmp(fun, "PetscReallocAlign"))));
}

static void PrintOutOfMemory(const char *fun, const char *mess)
{
  PetscMPIInt rank = 0;

  (void)MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  (void)fprintf(stderr,
                "[%d] kergs: out of memory: an allocation in %s failed, this process could not get the memory it asked for. Fewer "
                "grains per rank (more ranks, a smaller -lattice_n or -random_n), or more memory for the job\n",
                (int)rank, mess && mess[0] ? mess : fun);
}

static PetscErrorCode OutOfMemoryHandler(MPI_Comm comm, int line, const char *fun, const char *file, PetscErrorCode n, PetscErrorType p,
                                         const char *mess, void *ctx)
{
  if (p == PETSC_ERROR_INITIAL && AllocationFailed(fun, n)) PrintOutOfMemory(fun, mess);
  return PetscTraceBackErrorHandler(comm, line, fun, file, n, p, mess, ctx);
}

PetscErrorCode KergsPushErrorHandler(void)
{
  PetscFunctionBeginUser;
  PetscCall(PetscPushErrorHandler(OutOfMemoryHandler, NULL));
  PetscFunctionReturn(0);
}

/* The first error raised while errors are held: what PETSc's handler receives (its message formatted, up to PETSc's
   2,048 characters), kept to raise it again once the file is closed. */
static struct {
  PetscBool      set;
  PetscErrorCode code;
  int            line;
  char           fun[128], file[256], message[2048];
} Held;

static PetscErrorCode HoldHandler(MPI_Comm comm, int line, const char *fun, const char *file, PetscErrorCode n, PetscErrorType p,
                                  const char *mess, void *ctx)
{
  (void)comm;
  (void)ctx;
  /* a failed allocation is one rank's: that rank would close the file while the others go on reading it, and both sides
     would wait for each other. It ends the run at once, as main does after any error (status 1, KERGS_EXIT_ERROR). */
  if (p == PETSC_ERROR_INITIAL && AllocationFailed(fun, n)) {
    PrintOutOfMemory(fun, mess);
    (void)MPI_Abort(MPI_COMM_WORLD, 1);
  }
  if (p == PETSC_ERROR_INITIAL && !Held.set) {
    Held.set  = PETSC_TRUE;
    Held.code = n;
    Held.line = line;
    (void)PetscStrncpy(Held.fun, fun ? fun : "", sizeof(Held.fun));
    (void)PetscStrncpy(Held.file, file ? file : "", sizeof(Held.file));
    (void)PetscStrncpy(Held.message, mess ? mess : "", sizeof(Held.message));
  }
  return n;
}

PetscErrorCode KergsErrorsHoldBegin(void)
{
  PetscFunctionBeginUser;
  Held.set = PETSC_FALSE;
  PetscCall(PetscPushErrorHandler(HoldHandler, NULL));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsErrorsHoldEnd(void)
{
  PetscFunctionBeginUser;
  PetscCall(PetscPopErrorHandler());
  PetscFunctionReturn(0);
}

PetscErrorCode KergsErrorsRaiseHeld(MPI_Comm comm, PetscErrorCode held, const char role[], const char path[])
{
  PetscMPIInt failed = held ? 1 : 0, all;
  MPI_Comm    where;
  char       *named = NULL;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Allreduce(&failed, &all, 1, MPI_INT, MPI_MIN, comm));
  if (!held) PetscFunctionReturn(0);
  where = all ? comm : PETSC_COMM_SELF; /* printed once when every rank holds one, else by each rank that does */
  PetscCheck(Held.set, where, held, "%s %s: an error was raised while it was open", role, path);
  /* HDF5's own failures (a corrupt file: "Error in HDF5 call H5Lexists() Status -1") do not name the file */
  PetscCall(PetscStrstr(Held.message, path, &named));
  if (named) SETERRQ(where, Held.code, "%s [raised in %s() at %s:%d]", Held.message, Held.fun, Held.file, Held.line);
  SETERRQ(where, Held.code, "%s %s: %s [raised in %s() at %s:%d]", role, path, Held.message, Held.fun, Held.file, Held.line);
}

void KergsReturnFreedMemory(void)
{
#if defined(__GLIBC__)
  /* Debian's libsuperlu_dist (loaded with PETSc; kergs does not use it) sets M_MMAP_MAX = 0 and M_TRIM_THRESHOLD = -1
     when it is loaded: every block then comes from the heap and nothing freed is ever returned to the system, so a
     step's peak resident memory is the sum of everything its phases ever held, fragmented. Blocks of 128 KB or more
     are mapped on their own again and heap tops above 128 KB trimmed (glibc's initial values, now fixed). The price
     is the page faults of a step's new blocks, in the assembly (both measured in docs/scaling.md, "Memory"). */
  (void)mallopt(M_MMAP_MAX, 65536);
  (void)mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  (void)mallopt(M_TRIM_THRESHOLD, 128 * 1024);
#endif
}

PetscErrorCode KergsViewFromOptions(MPI_Comm comm, const char prefix[], const char option[], PetscErrorCode (*view)(void *, PetscViewer),
                                    void *obj)
{
  PetscViewer       viewer;
  PetscViewerFormat format;
  PetscBool         set;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetViewer(comm, NULL, prefix, option, &viewer, &format, &set));
  if (!set) PetscFunctionReturn(0);
  PetscCall(PetscViewerPushFormat(viewer, format));
  PetscCall((*view)(obj, viewer));
  PetscCall(PetscViewerPopFormat(viewer));
  PetscCall(PetscViewerDestroy(&viewer));
  PetscFunctionReturn(0);
}

const char *KergsGetVersion(void) { return KERGS_VERSION; }

PetscErrorCode KergsProvenanceGet(MPI_Comm comm, KergsProvenance *p)
{
  PetscMPIInt rank;
  int         len = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(p, sizeof(*p)));
  p->version = KERGS_VERSION;
  PetscCallMPI(MPI_Comm_size(comm, &p->ranks));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    const time_t now = time(NULL);
    struct tm    utc;
    if (!gmtime_r(&now, &utc) || !strftime(p->date, sizeof(p->date), "%Y-%m-%dT%H:%M:%SZ", &utc))
      PetscCall(PetscStrcpy(p->date, "unknown"));
    if (RunOptions)
      PetscCall(PetscStrallocpy(RunOptions, &p->options));
    else
      PetscCall(PetscOptionsGetAll(NULL, &p->options));
    len = (int)strlen(p->options) + 1;
  }
  PetscCallMPI(MPI_Bcast(p->date, (int)sizeof(p->date), MPI_CHAR, 0, comm));
  PetscCallMPI(MPI_Bcast(&len, 1, MPI_INT, 0, comm));
  if (rank != 0) PetscCall(PetscMalloc1(len, &p->options));
  PetscCallMPI(MPI_Bcast(p->options, len, MPI_CHAR, 0, comm));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsProvenanceDestroy(KergsProvenance *p)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(p->options));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsProvenanceSetOptions(MPI_Comm comm)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage()); /* its finalizer frees the copy */
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(PetscFree(RunOptions));
  if (rank == 0) PetscCall(PetscOptionsGetAll(NULL, &RunOptions));
  PetscFunctionReturn(0);
}
