/* kergs operators: the linear maps of one step as PETSc objects (DESIGN.md sections 2 and 6).
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
struct _p_KergsOperators {
  MPI_Comm comm;
  PetscInt ndof_disk; /* free DOFs per disk: KERGS_DIM (+ KERGS_NROT if frictional) */
  PetscInt ncomp;     /* components per contact: 1 (frictionless) or KERGS_DIM */
  PetscInt nfreewalls, ndrivenwalls;
  PetscInt *wall_dof; /* per wall: global index of its first free DOF, or of its first given DOF (driven) */
  Mat HfT;            /* H_f^T */
  Mat Hf;             /* H_f, NULL until KergsOperatorsGetHf */
  Mat HgT;            /* H_g^T, NULL when the scene has no driven wall */
  Mat W;              /* H_f^T M^-1 H_f, (MPI)SBAIJ with block size ncomp: upper block triangle */
  PetscBool W_active_only; /* W couples the active contacts only (KergsOperatorsAssembleW) */
  Vec Minv;           /* diagonal of M^-1 over free DOFs */
  Vec Vf;             /* free velocities V_f (V_f^- on entry of a step, V_f^+ after the update) */
  Vec Rd;             /* impulse of external forces over the step */
  Vec Vg;             /* given velocities V_g^+ (NULL without driven walls) */
  Vec vd;             /* free local velocity v^d */
  Vec r, v;           /* contact impulses and local velocities */
  PetscInt   nfree, nfree_local, ngiven; /* free DOFs (global, local), given DOFs */
  PetscInt   dstart;                      /* first disk of this rank when the DOF vectors were built */
  PetscReal  nnz_Hf, nnz_W;               /* global nonzeros of H_f and of the whole W (both triangles) when built */
};

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
PETSC_EXTERN PetscErrorCode KergsOperatorsGetHf(KergsOperators, Mat *);
/* W with both triangles stored, (MPI)BAIJ with block size ncomp ((MPI)AIJ when ncomp = 1), for the users that need
   whole rows (a new matrix: MatDestroy it) */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetFullW(KergsOperators, Mat *);
/* r <- impulses stored in the contacts; contacts <- r (after a solve; the local velocities stay in ops->v) */
PETSC_EXTERN PetscErrorCode KergsOperatorsGetImpulses(KergsOperators, KergsContacts);
PETSC_EXTERN PetscErrorCode KergsOperatorsSetImpulses(KergsOperators, KergsContacts);
/* V_f^+ = V_f^- + M^-1 (H_f r + R^d) (needs H_f), then copy the new velocities into the owned disks (velocities, angular
   velocities when the scene rotates) and the free walls (broadcast from their owner, the last rank) */
PETSC_EXTERN PetscErrorCode KergsOperatorsUpdateVelocities(KergsOperators, KergsScene);
/* Global free DOF index of the first DOF of the disk of global index i (scene->gidx[local index]) */
#define KergsOperatorsDiskDof(ops, i) ((i) * (ops)->ndof_disk)
PETSC_EXTERN PetscErrorCode KergsOperatorsDestroy(KergsOperators *);

#endif
