/* kergs: log events of the phases of a step, registered once. */
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
