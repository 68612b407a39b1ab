/* kergs sweep: the non-linear Gauss-Seidel sweep over a rank's contacts (Algorithm 2), reading W's block
   CSR arrays directly (one block row of ncomp x ncomp blocks per contact), whole (AIJ, BAIJ) or upper block
   triangle only (SBAIJ). Gauss-Seidel inside a rank, Jacobi across ranks: the impulses of other ranks'
   contacts are scattered once per sweep (docs/design.md: parallel layout).
   Regularised variants (Algorithm 6, NLGS-Jac) pass an extra right-hand side per component and
   replacement diagonal blocks. */
#ifndef KERGS_SWEEP_H
#define KERGS_SWEEP_H

#include <kergs/law.h>
#include <petscmat.h>

typedef struct _p_KergsSweep *KergsSweep;

/* Measures of one sweep, reduced over ranks by KergsSweepRun.
   dr = r_new - r_old over the sweep, r = r_new, Waa = W's own diagonal blocks (not Wdiag_override); the mean
   is over all contacts, inactive ones included. When a denominator vanishes (r_new = 0 everywhere) a measure
   is 0 if nothing changed and 1 otherwise. */
typedef struct {
  PetscReal quad; /* sqrt( sum dr^T Waa dr / sum r^T Waa r ): W-weighted relative change of r (LMGC90 "Quad" spirit) */
  PetscReal maxm; /* max sqrt(dr^T Waa dr) / mean sqrt(r^T Waa r) over contacts (LMGC90 "Maxm" spirit) */
} KergsSweepMeasures;

PETSC_EXTERN PetscErrorCode KergsSweepCreate(MPI_Comm, KergsSweep *);
/* Take W (assembled (seq|mpi)sbaij or (seq|mpi)baij with block size ncomp, or (seq|mpi)aij when ncomp = 1, for the current contacts, row
   and column layouts equal, ncomp rows per local contact) and per-contact mu and activity. Keeps a reference to W and its CSR arrays, and
   the pointers mu and active (owned by the caller, read at every sweep). Calling it again resets first; if W's values change, call it
   again. */
PETSC_EXTERN PetscErrorCode KergsSweepSetUp(KergsSweep, Mat W, PetscInt ncomp, const PetscReal *mu, const PetscBool *active);
/* The predictive gap rule's normal velocity offsets already added to v^d's normal components (per contact, the
   caller's array, NULL: none), so that the velocity error's scale is the free velocity without them (a contact far
   open would otherwise make every other error look small). After KergsSweepSetUp. */
PETSC_EXTERN PetscErrorCode KergsSweepSetGapVelocities(KergsSweep, const PetscReal *gapvel);
/* The diagonal blocks W_aa of the local contacts, n blocks of ncomp x ncomp row-major, into blocks (the caller's). */
PETSC_EXTERN PetscErrorCode KergsSweepGetDiagonalBlocks(KergsSweep, PetscReal *blocks);
/* One sweep: r (local array, updated in place) for v = W r + vd (+ extra). Collective.
   extra (optional): n*ncomp values added to each contact's right-hand side, fixed during the sweep.
   Wdiag_override (optional): n blocks of ncomp x ncomp used by the law instead of W_aa (NLGS-Jac: W_aa + Z_aa). */
PETSC_EXTERN PetscErrorCode KergsSweepRun(KergsSweep, Vec r, Vec vd, const PetscReal *extra, const PetscReal *Wdiag_override,
                                          KergsSweepMeasures *);
/* Natural-map residual |e| / max(|r|, |p|) (KergsLawNaturalResidualScaled, law.h), e_a = r_a - p_a, p_a = proj(r_a - rho_a v_a),
   with v = W r + vd; also returns v. Collective. rho = 1 / W_aa,nn per contact (law.h). 0 for the zero solution of an open
   problem, 1 at r = 0 otherwise. */
PETSC_EXTERN PetscErrorCode KergsSweepNaturalResidual(KergsSweep, Vec r, Vec vd, Vec v, PetscReal *res);
/* How far r is from solving the original problem, with v = W r + vd (returned in v). Collective.
   natural:  the natural-map residual above, |e| / max(|r|, |p|): relative, so that tolerances mean the same at any load.
   scale:    max(|r|, |p|), its denominator (impulse units): |e| = natural * scale, for solvers whose inner tolerances
             are absolute.
   velocity: max_a |e_a| / rho_a over the largest velocity of an active contact (its free velocity v^d_a or the change
             W r produced): the law's worst violation in velocity, relative to the problem's velocities. Unlike the
             natural residual it does not shrink when r grows by a self-equilibrated part (ker W), which is how every
             solver's iterates run away on a problem without solution (the straight row of confine5_straight). */
typedef struct {
  PetscReal natural, scale, velocity;
} KergsResiduals;
PETSC_EXTERN PetscErrorCode KergsSweepResiduals(KergsSweep, Vec r, Vec vd, Vec v, KergsResiduals *);
/* This rank's time in the sweeps' arithmetic since KergsSweepSetUp, messages and reductions excluded (its share of the
   work, as the partition measures it). */
PETSC_EXTERN PetscErrorCode KergsSweepGetComputeSeconds(KergsSweep, PetscLogDouble *);
PETSC_EXTERN PetscErrorCode KergsSweepReset(KergsSweep);
PETSC_EXTERN PetscErrorCode KergsSweepDestroy(KergsSweep *);

#endif
