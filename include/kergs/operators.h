/* kergs operators: the linear maps of one step as PETSc objects (docs/design.md: notation, parallel layout).
   Free DOFs: per disk KERGS_DIM translations, plus KERGS_NROT rotations only when the scene is
   frictional (frictionless contacts exert no torque on disks); then KERGS_DIM translations per free
   wall, owned by the last rank. Given DOFs: KERGS_DIM translations per driven wall, owned by rank 0.
   Contact components: normal, plus tangential only when the scene is frictional.

   HfT = H_f^T (contact components x free DOFs) is assembled (each contact's rows are local to its owner);
   H_f itself is its explicit transpose, built on demand. W = H_f^T M^-1 H_f is a Mat over
   contact components stored by ncomp x ncomp blocks, one block row per contact, upper block triangle only
   ((MPI)SBAIJ with block size ncomp, 1 when frictionless; W is symmetric). */
#ifndef KERGS_OPERATORS_H
#define KERGS_OPERATORS_H

#include <kergs/detect.h>
#include <petscmat.h>

typedef struct _p_KergsOperators *KergsOperators;

/* The layout of the unknowns (KergsOperatorsGetLayout). Free DOFs: disks in global-index order, ndof_disk each
   (KergsOperatorsDiskDof), then KERGS_DIM per free wall (on the last rank); wall_dof[w] is wall w's first free DOF
   (free wall) or first given DOF (driven wall). Contact components: ncomp per contact, contacts in global order. */
typedef struct {
  PetscInt        ncomp;     /* components per contact: 1 (frictionless) or KERGS_DIM */
  PetscInt        ndof_disk; /* free DOFs per disk: KERGS_DIM (+ KERGS_NROT when the disks rotate) */
  PetscInt        ndisks;    /* disks (the first ndisks * ndof_disk free DOFs) */
  PetscInt        nfreewalls, ndrivenwalls;
  PetscInt        nfree, nfree_local, ngiven; /* free DOFs (global, this rank's), given DOFs */
  const PetscInt *wall_dof;
} KergsDofLayout;

PETSC_EXTERN PetscErrorCode KergsOperatorsCreate(MPI_Comm, KergsOperators *);
/* Build H_f^T, H_g^T, M^-1, W (over all pairs), V_f^-, V_g^+, R^d, v^d for the current scene and contact set:
   AssembleH (keeping H) then AssembleW. */
PETSC_EXTERN PetscErrorCode KergsOperatorsAssemble(KergsOperators, KergsScene, KergsContacts);
/* The two halves, for a caller that frees H before W exists (the time step, so that its peak memory is the larger of
   H and W, not their sum). AssembleH: the DOF vectors, v^d, and r, v (the step's other objects are destroyed); H_f^T
   and H_g^T stay when keep, else each is freed once v^d has its part. AssembleW: W, from the contacts and M^-1 (no H
   needed); with activeonly, only the blocks between active contacts (KergsContactIsActive) and the diagonal blocks:
   an inactive contact has r = 0 throughout the solve (the solver zeroes its warm start), so its coupling adds zeros
   to the others' sums and its own sum is not needed (its law gives r = 0 whatever v); NLGS then gives the same
   impulses to the bit, from a W whose size is about that of the active set. BuildHf: H_f^T again (for the velocity
   update). Release*: destroy them. */
PETSC_EXTERN PetscErrorCode KergsOperatorsAssembleH(KergsOperators, KergsScene, KergsContacts, PetscBool keep);
PETSC_EXTERN PetscErrorCode KergsOperatorsAssembleW(KergsOperators, KergsScene, KergsContacts, PetscBool activeonly);
PETSC_EXTERN PetscErrorCode KergsOperatorsBuildHf(KergsOperators, KergsScene, KergsContacts);
PETSC_EXTERN PetscErrorCode KergsOperatorsReleaseH(KergsOperators);
PETSC_EXTERN PetscErrorCode KergsOperatorsReleaseW(KergsOperators);
/* W with both triangles stored, (MPI)BAIJ with block size ncomp ((MPI)AIJ when ncomp = 1), for the users that need
   whole rows: a new reference (MatDestroy it), shared on several ranks with the operators (do not modify it) */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetFullW(KergsOperators, Mat *);
/* Whether KergsOperatorsAssembleW also assembles W with both triangles on several ranks, for KergsOperatorsGetFullW:
   PETSc's conversion of a parallel upper triangle goes entry by entry (0.4 s a step on 2 ranks at 160,000 contacts),
   a second assembly costs a third of that. On one rank the conversion copies, and W is converted as before. */
PETSC_EXTERN PetscErrorCode KergsOperatorsSetBothTriangles(KergsOperators, PetscBool);
/* A contact problem given as data, not assembled from a scene (an FCLib file): W (symmetric, rows and columns ordered
   contact by contact, ncomp components each) in compressed rows over the whole problem, and q = v^d, both given whole on
   every rank; this rank takes nlocal contacts, rank after rank. Builds W (upper block triangle, as AssembleW), v^d, and
   r = 0, v = v^d; no H nor DOF vectors (KergsOperatorsGetH gives NULL). Collective. */
PETSC_EXTERN PetscErrorCode KergsOperatorsSetProblem(KergsOperators, PetscInt nlocal, PetscInt ncomp, const PetscInt rowptr[],
                                                     const PetscInt colind[], const PetscReal val[], const PetscReal q[]);
/* r <- impulses stored in the contacts; contacts <- r (after a solve; the local velocities stay in ops->v) */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetImpulses(KergsOperators, KergsContacts);
PETSC_EXTERN PetscErrorCode KergsOperatorsSetImpulses(KergsOperators, KergsContacts);
/* V_f^+ = V_f^- + M^-1 (H_f r + R^d) (needs H_f), then copy the new velocities into the owned disks (velocities, angular
   velocities when the scene rotates) and the free walls (broadcast from their owner, the last rank) */
PETSC_EXTERN PetscErrorCode KergsOperatorsUpdateVelocities(KergsOperators, KergsScene);
/* Accessors. Objects of the current step, NULL when not built (or released). */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetLayout(KergsOperators, KergsDofLayout *);
/* r (impulses), v (local velocities) and v^d over the contact components; any argument may be NULL */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetContactVectors(KergsOperators, Vec *r, Vec *v, Vec *vd);
/* V_f, M^-1 (its diagonal), R^d over the free DOFs, V_g over the given DOFs (NULL without driven walls) */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetDofVectors(KergsOperators, Vec *Vf, Vec *Minv, Vec *Rd, Vec *Vg);
/* H_f^T, H_g^T */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetH(KergsOperators, Mat *HfT, Mat *HgT);
/* W as stored (upper block triangle, (MPI)SBAIJ), and whether it couples only the active contacts */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetW(KergsOperators, Mat *W, PetscBool *active_only);
/* Nonzeros of H_f and of the whole W (both triangles) when last built */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetNonzeros(KergsOperators, PetscReal *nnz_Hf, PetscReal *nnz_W);
/* Global free DOF index of the first DOF of the disk of global index i, in a layout */
#define KergsDiskDof(layout, i) ((i) * (layout)->ndof_disk)
PETSC_EXTERN PetscErrorCode KergsOperatorsDestroy(KergsOperators *);

#endif
