/* kergs sample: a packing of disks saved by one run for another to start from (HDF5, docs/results.md):
     /sample/x (n x KERGS_DIM), /sample/v, /sample/rot, /sample/omega, /sample/radius, /sample/material, /sample/id
   and attributes ndisks, time on /sample; /sample/box; /sample/contacts, the contact forces that hold the packing.
   Written atomically; read by KergsSampleRead (kergs/scene.h), the disk source "file", and KergsSampleReadForces. */
#ifndef KERGS_SAMPLE_H
#define KERGS_SAMPLE_H

#include <kergs/detect.h>

/* The scene's disks and box, and the forces of the contacts that carry one (none when contacts is NULL or no step was
   taken). Collective. */
PETSC_EXTERN PetscErrorCode KergsSampleWrite(KergsScene, KergsContacts, const char path[]);
/* The first step's warm start: the contact forces of the sample file the scene's disks were read from, as impulses of the
   scene's time step, restored as the contacts' previous state before their first detection (after the initial
   partition). Nothing when the disks are not from a sample or the sample records no contacts. With contacts NULL, only
   reads and checks them: a run calls it so before it writes anything, so that a bad file loses nothing. nforces (may be
   NULL): how many forces were restored, over all ranks. Collective. */
PETSC_EXTERN PetscErrorCode KergsSampleReadForces(KergsScene, KergsContacts, PetscInt *nforces);

#endif
