/* kergs sample: a packing of disks saved by one run and read by another (HDF5, docs/results.md):
     /sample/x (n x KERGS_DIM), /sample/v, /sample/rot, /sample/omega, /sample/radius, /sample/material, /sample/id
   and attributes ndisks, time on /sample. Written atomically; reading checks every size. */
#ifndef KERGS_SAMPLE_H
#define KERGS_SAMPLE_H

#include <kergs/scene.h>

PETSC_EXTERN PetscErrorCode KergsSampleWrite(KergsScene, const char path[]);
/* Replace the scene's disks with those of the file (materials must exist in the scene). */
PETSC_EXTERN PetscErrorCode KergsSampleRead(KergsScene, const char path[]);

#endif
