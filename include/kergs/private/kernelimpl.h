/* kergs kernel, private: the kernel projector's fields, for src/solver/kernel.c only; other components go through
   the accessors of kergs/kernel.h. */
#ifndef KERGS_KERNELIMPL_H
#define KERGS_KERNELIMPL_H

#include <kergs/kernel.h>

struct _p_KergsKernel {
  MPI_Comm        comm;
  char            prefix[256]; /* options prefix (KergsKernelSetOptionsPrefix), before kernel_ */
  char            solver[32];  /* -kernel_solver: auto, cholmod, mumps */
  char            used[32];    /* the factorization package actually used this step */
  KergsKernelDiag diagtype;    /* -kernel_diag */
  PetscReal       omega;
  /* this step's reduced problem */
  Mat        Hr;                   /* reduced H_f^T: kept contact components x kept DOFs */
  IS         keep_rows, keep_cols; /* kept DOFs (global free DOF numbers), kept contact components */
  Mat        A, F;                 /* A = Hr^T Hr (DOF space) and its factor */
  Mat        Z;                    /* MATSHELL over all contact components: x -> omega P x */
  PetscReal *Zdiag;                /* per local contact, ncomp x ncomp row-major blocks of Z */
  PetscInt   ncomp, nlocal;        /* components per contact, local contacts */
  /* statistics of this step */
  PetscInt  ncols;             /* contact components (columns of H_f) */
  PetscInt  nrows;             /* free DOFs (rows of H_f) */
  PetscInt  rank;              /* rank of H_f */
  PetscInt  floating_grains;   /* grains without contact */
  PetscInt  peeled_contacts;   /* contacts removed because they end on a single-contact grain */
  PetscInt  deficiency_peeled; /* rank lost by the peeled grains */
  PetscInt  null_pivots;       /* remaining deficiency found by the factorization */
  PetscInt  nnz_factor;        /* entries of the factor (0 when the package does not tell) */
  PetscReal factor_seconds, diag_seconds;
  /* work */
  Vec        xr, yr, ar, br; /* reduced contact and DOF vectors */
  VecScatter to_reduced;     /* all contact components -> kept ones */
  /* added with the implementation (src/kernel.c) */
  PetscReal          null_pivot_tol;        /* -kernel_null_pivot_tol: MUMPS CNTL(3); CHOLMOD is rejected above condition 1/tol */
  PetscReal          check_tol;             /* -kernel_check_tol: largest |H_f P x| / |H_f x| accepted after each factorization */
  PetscInt           diag_batch;            /* -kernel_diag_batch: contacts per rank in one block of right-hand sides (exact diag) */
  PetscInt           floating_dofs;         /* DOFs of bodies (grains and free walls) without contact */
  PetscInt           single_contact_grains; /* grains with exactly one contact before peeling */
  PetscInt           kept_dofs, kept_comps; /* sizes of the reduced problem: rows of A, rows of Hr */
  PetscInt          *kept_offset;           /* per local contact: local index of its first component in xr, -1 if peeled */
  PetscReal          check_error;           /* this step's |H_f P x| / |H_f x| on a pseudo-random x */
  PetscBool          check_failed;          /* check_error above -kernel_check_tol even with MUMPS: this step's projector misses ker H_f */
  PetscReal          cond_estimate;         /* CHOLMOD only: |A|_1 |A^-1 v|_1 / |v|_1 for a pseudo-random v (0 otherwise) */
  PetscBool          fell_back;             /* CHOLMOD was chosen but MUMPS used this step (CHOLMOD rejected, or A singular by its sizes) */
  PetscBool          nnz_known;             /* nnz_factor was reported by the package (MUMPS INFOG(29)) */
  PetscInt           nsetups, symbolic_reuses, fallbacks; /* over the kernel's life */
  PetscInt           cholmod_pause;                       /* set-ups left before CHOLMOD is tried again after a rejection */
  PetscInt           napply;                              /* projector applications since the last SetUp */
  PetscReal          apply_seconds;                       /* their total time */
  PetscInt           pattern_n, pattern_nnz;              /* local rows and nonzeros of the A that F's symbolic factor was made for */
  unsigned long long pattern_hash;                        /* hash of its local CSR pattern */
  const PetscBool   *active;                              /* per local contact (KergsKernelSetActive); NULL: every contact */
  PetscBool          active_only;       /* -kernel_active_only: H_f over the active contacts instead of all potential ones */
  PetscInt           inactive_contacts; /* contacts left out because inactive: r = 0 there, not an unknown */
};

#endif
