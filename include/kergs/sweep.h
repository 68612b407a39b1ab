/* kergs sweep: the non-linear Gauss-Seidel sweep over a rank's contacts (Algorithm 2), reading W's block
   CSR arrays directly (one block row of ncomp x ncomp blocks per contact), whole (AIJ, BAIJ) or upper block
   triangle only (SBAIJ). Gauss-Seidel inside a rank, Jacobi across ranks: the impulses of other ranks'
   contacts are scattered once per sweep (DESIGN.md section 6).
   Regularised variants (Algorithm 6, NLGS-Jac) pass an extra right-hand side per component and
   replacement diagonal blocks. */
#ifndef KERGS_SWEEP_H
#define KERGS_SWEEP_H

#include <kergs/law.h>
#include <petscmat.h>

typedef struct _p_KergsSweep *KergsSweep;
struct _p_KergsSweep {
  MPI_Comm comm;
  PetscInt ncomp, n;          /* components per contact, local contacts */
  Mat      W, Ad, Ao;         /* W and its local diagonal / off-process blocks (Ao NULL when W is sequential) */
  PetscBool blocked;          /* W is (seq|mpi)(s)baij with block size ncomp; otherwise (seq|mpi)aij with ncomp = 1 */
  PetscBool upper;            /* W is (seq|mpi)sbaij: only the blocks W_alpha,beta with beta >= alpha are stored */
  const PetscInt    *ai, *aj, *bi, *bj; /* block CSR of Ad and Ao: block rows = local contacts */
  const PetscScalar *aa, *ba;           /* their values, ncomp*ncomp per block, each block column by column */
  PetscReal *Wdiag;           /* whole storage: n blocks of ncomp x ncomp, W_alpha,alpha row-major (NULL with upper storage, which
                                 the sweep reads in place); see KergsSweepGetDiagonalBlocks */
  PetscReal *mu;              /* per contact (the caller's array; NULL: frictionless) */
  PetscBool *active;          /* per contact: predicted gap <= 0 (the caller's array; NULL: all active) */
  Vec        rghost;          /* off-process impulses, ordered as Ao's (block) columns */
  VecScatter ghost_scatter;
  PetscInt   norows, *orows;  /* several ranks: the local contacts coupled to other ranks' (sorted) */
  PetscReal *corr;            /* several ranks: per coupled row, the other ranks' W r (fixed in a sweep) */
  PetscInt  *dsplit;          /* per local contact a: [start, end) of its own block W_aa in aj (skipped by the sweep); NULL with
                                 upper storage, where W_aa is the first block of row a */
  /* upper storage only */
  PetscReal   *acc;           /* per local component: sum_{beta < alpha local} W_beta,alpha^T r_beta (new), within a sweep */
  Vec          blower;        /* W's layout: the lower ranks' coupling B^T r, scattered back (added) from them */
  Vec          ylower;        /* like rghost: this rank's B^T r, sent to the higher ranks */
  VecScatter   lower_scatter; /* a copy of ghost_scatter, used reversed, in flight together with it */
  PetscInt    *ubi, *ubj;     /* the copy of the off-process part (upper: columns right of this rank), owned */
  PetscScalar *uba;
  PetscLogDouble compute_seconds; /* this rank's time in the sweeps' arithmetic since KergsSweepSetUp, messages and
                                     reductions excluded: its share of the work, as the partition measures it */
};

/* Measures of one sweep, reduced over ranks by KergsSweepRun.
   dr = r_new - r_old over the sweep, r = r_new, Waa = W's own diagonal blocks (not Wdiag_override); the mean
   is over all contacts, inactive ones included. When a denominator vanishes (r_new = 0 everywhere) a measure
   is 0 if nothing changed and 1 otherwise. */
typedef struct {
  PetscReal quad; /* sqrt( sum dr^T Waa dr / sum r^T Waa r ): W-weighted relative change of r (LMGC90 "Quad" spirit) */
  PetscReal maxm; /* max sqrt(dr^T Waa dr) / mean sqrt(r^T Waa r) over contacts (LMGC90 "Maxm" spirit) */
} KergsSweepMeasures;

PETSC_EXTERN PetscErrorCode KergsSweepCreate(MPI_Comm, KergsSweep *);
/* Take W (assembled (seq|mpi)sbaij or (seq|mpi)baij with block size ncomp, or (seq|mpi)aij when ncomp = 1, for the current contacts, row and column layouts
   equal, ncomp rows per local contact) and per-contact mu and activity. Keeps a reference to W and its CSR arrays, and the pointers mu and
   active (owned by the caller, read at every sweep). Calling it again resets first; if W's values change,
   call it again. */
PETSC_EXTERN PetscErrorCode KergsSweepSetUp(KergsSweep, Mat W, PetscInt ncomp, const PetscReal *mu, const PetscBool *active);
/* The diagonal blocks W_aa of the local contacts, n blocks of ncomp x ncomp row-major, into blocks (the caller's). */
PETSC_EXTERN PetscErrorCode KergsSweepGetDiagonalBlocks(KergsSweep, PetscReal *blocks);
/* One sweep: r (local array, updated in place) for v = W r + vd (+ extra). Collective.
   extra (optional): n*ncomp values added to each contact's right-hand side, fixed during the sweep.
   Wdiag_override (optional): n blocks of ncomp x ncomp used by the law instead of W_aa (NLGS-Jac: W_aa + Z_aa). */
PETSC_EXTERN PetscErrorCode KergsSweepRun(KergsSweep, Vec r, Vec vd, const PetscReal *extra, const PetscReal *Wdiag_override, KergsSweepMeasures *);
/* Natural-map residual sqrt(sum_a |r_a - proj(...)|^2) / max(|r|, tiny), with v = W r + vd; also returns v. Collective.
   rho = 1 / W_aa,nn per contact (law.h). When r = 0 it is the absolute value (0 for the zero solution of an open problem). */
PETSC_EXTERN PetscErrorCode KergsSweepNaturalResidual(KergsSweep, Vec r, Vec vd, Vec v, PetscReal *res);
PETSC_EXTERN PetscErrorCode KergsSweepReset(KergsSweep);
PETSC_EXTERN PetscErrorCode KergsSweepDestroy(KergsSweep *);

#endif
