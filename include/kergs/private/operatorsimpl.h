/* kergs operators, private: the operators object's fields, for src/operators/ only; every other component goes
   through the accessors of kergs/operators.h. */
#ifndef KERGS_OPERATORSIMPL_H
#define KERGS_OPERATORSIMPL_H

#include <kergs/operators.h>

struct _p_KergsOperators {
  MPI_Comm  comm;
  PetscInt  ndof_disk; /* free DOFs per disk: KERGS_DIM (+ KERGS_NROT if frictional) */
  PetscInt  ncomp;     /* components per contact: 1 (frictionless) or KERGS_DIM */
  PetscInt  nfreewalls, ndrivenwalls;
  PetscInt *wall_dof;                   /* per wall: global index of its first free DOF, or of its first given DOF (driven) */
  Mat       HfT;                        /* H_f^T */
  Mat       HgT;                        /* H_g^T, NULL when the scene has no driven wall */
  Mat       W;                          /* H_f^T M^-1 H_f, (MPI)SBAIJ with block size ncomp: upper block triangle */
  PetscBool W_active_only;              /* W couples the active contacts only (KergsOperatorsAssembleW) */
  PetscBool both_triangles;             /* several ranks: W with both triangles assembled too (KergsOperatorsSetBothTriangles) */
  Mat       Wboth;                      /* that W, (MPI)BAIJ ((MPI)AIJ when ncomp = 1), or NULL */
  Vec       Minv;                       /* diagonal of M^-1 over free DOFs */
  Vec       Vf;                         /* free velocities V_f (V_f^- on entry of a step, V_f^+ after the update) */
  Vec       Rd;                         /* impulse of external forces over the step */
  Vec       Vg;                         /* given velocities V_g^+ (NULL without driven walls) */
  Vec       vd;                         /* free local velocity v^d */
  Vec       r, v;                       /* contact impulses and local velocities */
  PetscInt  nfree, nfree_local, ngiven; /* free DOFs (global, local), given DOFs */
  PetscInt  dstart;                     /* first disk of this rank when the DOF vectors were built */
  PetscReal nnz_Hf, nnz_W;              /* global nonzeros of H_f and of the whole W (both triangles) when built */
};

/* What the assembly reads from the scene and the contacts, fetched once per call through their accessors. */
typedef struct {
  KergsDisks          D;
  PetscInt            nwalls;
  const KergsWall    *walls;
  PetscInt            ncontacts, start; /* owned contacts and the global index of the first */
  KergsContact       *c;
  PetscInt            nforeign; /* foreign contacts (kergs/detect.h) and their global indices */
  const KergsContact *foreign;
  const PetscInt     *foreign_index;
  KergsActivity       activity;
} StepData;
PETSC_INTERN PetscErrorCode KergsOperatorsGetStepData(KergsOperators, KergsScene, KergsContacts, StepData *);

/* One row of H^T restricted to one contact's bodies: its columns (free or given DOFs) and values. */
typedef struct {
  PetscInt  ncol;
  PetscInt  col[2 * (KERGS_DIM + KERGS_NROT)];
  PetscReal val[2 * (KERGS_DIM + KERGS_NROT)];
} HtRow;
/* Row c (0 normal, 1 tangential) of contact ct, split into its free part (H_f^T) and given part (H_g^T)
   (src/operators/operators.c). */
PETSC_INTERN void KergsOperatorsContactRows(KergsOperators, const StepData *, const KergsContact *ct, PetscInt c, HtRow *free,
                                            HtRow *given);

/* Global free DOF index of the first DOF of the disk of global index i */
#define KergsOperatorsDiskDof(ops, i) ((i) * (ops)->ndof_disk)

#endif
