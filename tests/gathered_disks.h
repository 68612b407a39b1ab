/* Every disk of a scene in global-index order, gathered on every rank: the reference the scene, detection and I/O
   tests compare against, whatever the partition. */
#ifndef KERGS_TESTS_GATHERED_DISKS_H
#define KERGS_TESTS_GATHERED_DISKS_H

#include "internals.h"

typedef struct {
  PetscInt   n;
  PetscReal *x, *v, *rot, *omega, *radius, *mass, *inertia;
  PetscInt  *id, *material;
} Disks;

static inline PetscErrorCode DisksGather(KergsScene s, Disks *all)
{
  const PetscInt n = s->ndisks;

  PetscFunctionBeginUser;
  all->n = n;
  PetscCall(PetscMalloc7(KERGS_DIM * n + 1, &all->x, KERGS_DIM * n + 1, &all->v, KERGS_NROT * n + 1, &all->rot, KERGS_NROT * n + 1,
                         &all->omega, n + 1, &all->radius, n + 1, &all->mass, n + 1, &all->inertia));
  PetscCall(PetscMalloc2(n + 1, &all->id, n + 1, &all->material));
  PetscCall(KergsSceneAllGatherReal(s, s->x, KERGS_DIM, all->x));
  PetscCall(KergsSceneAllGatherReal(s, s->v, KERGS_DIM, all->v));
  PetscCall(KergsSceneAllGatherReal(s, s->rot, KERGS_NROT, all->rot));
  PetscCall(KergsSceneAllGatherReal(s, s->omega, KERGS_NROT, all->omega));
  PetscCall(KergsSceneAllGatherReal(s, s->radius, 1, all->radius));
  PetscCall(KergsSceneAllGatherReal(s, s->mass, 1, all->mass));
  PetscCall(KergsSceneAllGatherReal(s, s->inertia, 1, all->inertia));
  PetscCall(KergsSceneAllGatherInt(s, s->id, 1, all->id));
  PetscCall(KergsSceneAllGatherInt(s, s->material, 1, all->material));
  PetscFunctionReturn(0);
}

static inline PetscErrorCode DisksFree(Disks *all)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree7(all->x, all->v, all->rot, all->omega, all->radius, all->mass, all->inertia));
  PetscCall(PetscFree2(all->id, all->material));
  PetscFunctionReturn(0);
}

#endif
