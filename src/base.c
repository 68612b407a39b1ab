/* kergs: log events of the phases of a step, registered once, and the personalised exchange of records. */
#include <kergs/base.h>

PetscLogEvent KERGS_Detect, KERGS_Assemble, KERGS_Solve, KERGS_Sweep, KERGS_Update, KERGS_IO, KERGS_Exchange;
PetscLogEvent KERGS_Factor, KERGS_KernelDiag, KERGS_KernelApply, KERGS_Predict, KERGS_Partition;

PetscErrorCode KergsInitializePackage(void)
{
  static PetscBool initialized = PETSC_FALSE;
  PetscClassId     classid;

  PetscFunctionBeginUser;
  if (initialized) PetscFunctionReturn(0);
  initialized = PETSC_TRUE;
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
  PetscFunctionReturn(0);
}

PetscErrorCode KergsExchangeRecords(MPI_Comm comm, size_t size, const PetscMPIInt sendcount[], const void *send, PetscMPIInt recvcount[], void *recv,
                                    PetscInt *nrecv)
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
