/* kergs sweep, private: the sweep's fields, for src/solver/sweep.c only; other components go through the accessors
   of kergs/sweep.h. */
#ifndef KERGS_SWEEPIMPL_H
#define KERGS_SWEEPIMPL_H

#include <kergs/sweep.h>

struct _p_KergsSweep {
  MPI_Comm           comm;
  PetscInt           ncomp, n;          /* components per contact, local contacts */
  Mat                W, Ad, Ao;         /* W and its local diagonal / off-process blocks (Ao NULL when W is sequential) */
  PetscBool          blocked;           /* W is (seq|mpi)(s)baij with block size ncomp; otherwise (seq|mpi)aij with ncomp = 1 */
  PetscBool          upper;             /* W is (seq|mpi)sbaij: only the blocks W_alpha,beta with beta >= alpha are stored */
  const PetscInt    *ai, *aj, *bi, *bj; /* block CSR of Ad and Ao: block rows = local contacts */
  const PetscScalar *aa, *ba;           /* their values, ncomp*ncomp per block, each block column by column */
  PetscReal         *Wdiag;             /* whole storage: n blocks of ncomp x ncomp, W_alpha,alpha row-major (NULL with upper storage, which
                                           the sweep reads in place); see KergsSweepGetDiagonalBlocks */
  PetscReal       *mu;                  /* per contact (the caller's array; NULL: frictionless) */
  PetscBool       *active;              /* per contact: predicted gap <= 0 (the caller's array; NULL: all active) */
  const PetscReal *gapvel;              /* per contact: the gap rule's normal velocity offset inside v^d (NULL: none) */
  Vec              rghost;              /* off-process impulses, ordered as Ao's (block) columns */
  VecScatter       ghost_scatter;
  PetscInt         norows, *orows; /* several ranks: the local contacts coupled to other ranks' (sorted) */
  PetscReal       *corr;           /* several ranks: per coupled row, the other ranks' W r (fixed in a sweep) */
  PetscInt        *dsplit;         /* per local contact a: [start, end) of its own block W_aa in aj (skipped by the sweep); NULL with
                                      upper storage, where W_aa is the first block of row a */
  /* upper storage only */
  PetscReal     *acc;           /* per local component: sum_{beta < alpha local} W_beta,alpha^T r_beta (new), within a sweep */
  Vec            blower;        /* W's layout: the lower ranks' coupling B^T r, scattered back (added) from them */
  Vec            ylower;        /* like rghost: this rank's B^T r, sent to the higher ranks */
  VecScatter     lower_scatter; /* a copy of ghost_scatter, used reversed, in flight together with it */
  PetscInt      *ubi, *ubj;     /* the copy of the off-process part (upper: columns right of this rank), owned */
  PetscScalar   *uba;
  PetscLogDouble compute_seconds; /* this rank's time in the sweeps' arithmetic since KergsSweepSetUp, messages and
                                     reductions excluded: its share of the work, as the partition measures it */
};

#endif
