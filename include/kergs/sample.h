/* kergs sample: a packing of disks saved by one run for another to start from (HDF5, docs/results.md):
     /sample/x (n x KERGS_DIM), /sample/v, /sample/rot, /sample/omega, /sample/radius, /sample/material, /sample/id
   and attributes ndisks, time on /sample. Written atomically; read by KergsSampleRead (kergs/scene.h), the disk
   source "file". */
#ifndef KERGS_SAMPLE_H
#define KERGS_SAMPLE_H

#include <kergs/scene.h>

PETSC_EXTERN PetscErrorCode KergsSampleWrite(KergsScene, const char path[]);

#endif
