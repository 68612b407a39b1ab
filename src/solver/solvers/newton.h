/* kergs solver type "newton" (newton.c): its state, shared with its linear algebra (newton_linear.c: the Jacobian
   J = A + B (W + sigma I) + eps I on W's pattern, and the solves of J d = -F), its working set (newton_working.c), its
   subdomain solver (newton_subdomain.c) and its two starts (newton_ip.c, newton_desaxce.c). Private to these files. */
#ifndef KERGS_NEWTON_H
#define KERGS_NEWTON_H

#include <kergs/private/solverimpl.h>
#include <kergs/kernel.h>
#include <petscksp.h>

typedef enum { NEWTON_PROX_NONE, NEWTON_PROX_IDENTITY, NEWTON_PROX_KERNEL } NewtonProx;

typedef struct {
  KSP ksp; /* J d = -F; prefix solver_ */
  /* -solver_prox kernel: the proximal term sigma P (r - r_c), P the projector on ker W over the active contacts */
  KergsKernel kernel;   /* P, through a factorization of H_f H_f^T per step */
  KSP         kprox;    /* J_P d = -F by GMRES preconditioned by the factorization of J (sigma I); prefix solver_prox_ */
  Mat         Jprox;    /* J_P = A + B (W + sigma P) + shift I, a MATSHELL */
  Vec         kx, kpx;  /* work: x and P x */
  KSP         kreuse;   /* J d = -F by GMRES preconditioned by the last factorization of an earlier J; prefix solver_reuse_ */
  Mat         Wfull, J; /* W with both triangles, and the Jacobian on its pattern */
  /* J's rows: every local contact, or those of the working set (below); on one rank with kergs's LU, in the AMD order
     of W over them, J factored in that (natural) order (PresortContacts) */
  PetscInt *order;   /* J's block row i is local contact order[i]; NULL: J in the contacts' order, every contact a row */
  PetscInt  nrows;   /* J's local block rows */
  PetscBool presort; /* decided once the linear solver's options are read (NewtonChoosePresorting) */
  Mat       Wsorted; /* W over J's rows in that AMD order: J's template */
  Vec       Fs, ds;  /* -F and d on J's rows, in J's order */
  /* without friction on one rank with kergs's LU (-solver_newton_cholesky): J's rows divided by B, the open contacts'
     columns moved to the right-hand side, J symmetric positive definite and factored by CHOLMOD (newton_linear.c) */
  PetscBool cholesky;    /* the option */
  PetscBool cholesky_ok; /* allowed by the linear solver's options (NewtonChoosePresorting) */
  PetscBool symmetric;   /* this step's J is in that form */
  PetscBool finite;      /* the J last assembled in that form is finite: else its solve fails without CHOLMOD */
  Vec       zs, ts;      /* work on J's rows: the open contacts' d, and W times it */
  /* -solver_newton_working_set: contacts open at the warm start and not closed by it are left out of J while they
     stay on the law's open piece (newton_working.c) */
  PetscBool  working_set; /* the option */
  PetscBool *in_J;        /* per local contact: a row of J */
  Mat        Wwork;       /* W over J's rows: J's template (NULL: W itself) */
  PetscInt   rebuilds;    /* times the last solve put contacts back into J and set it up again */
  PetscInt   left_out;    /* contacts left out of J at the end of the last solve (global) */
  /* several ranks, kergs's additive Schwarz: its preconditioning matrix, a shell whose subdomain matrices are computed
     from W's subdomain, extracted once per J, and the blocks of J's rows (newton_subdomain.c) */
  PetscBool  subdomains_from_w; /* -solver_newton_subdomains_from_w */
  Mat        Pschwarz;
  Vec        row_AB;              /* per row of J: A_k then B_k of the J last assembled */
  PetscInt   subdomains_computed; /* subdomain matrices built through W's subdomain in the last solve */
  PetscReal  eps_used;            /* its eps (sigma_used: its sigma) */
  Vec        F, d, Wd, rtry, utry, Ftry;
  Vec        rc, ueff;      /* the proximal centre, and the proximal problem's velocity */
  Vec        rplain;        /* the end of the plain attempt, kept while the smoothing phase runs */
  Vec        rstart, rbest; /* the first Attempt's start and end, kept while the second runs */
  PetscReal *A, *B;         /* per local contact, ncomp x ncomp row-major: J = A + B W */
  PetscReal *Aused, *Bused; /* the blocks of the Jacobian last assembled */
  PetscReal *Afact, *Bfact; /* the blocks of the Jacobian last factored */
  PetscReal  sigma_fact;    /* and its sigma */
  PetscReal *rho;           /* per local contact: rho_n = rho_t = rho_factor / W_aa,nn */
  PetscReal *rho_nat;       /* per local contact: 1 / W_aa,nn, the natural residual's */
  PetscInt  *diagblock;     /* per local block row: position of its own block in J's diagonal part */
  PetscInt   nalloc;
  /* options */
  PetscReal  rho_factor;           /* -solver_newton_rho */
  PetscReal  shift;                /* -solver_newton_shift */
  PetscReal  armijo;               /* -solver_newton_armijo: sufficient decrease of the merit */
  PetscInt   max_backtracks;       /* -solver_newton_max_backtracks */
  PetscReal  switch_tol;           /* -solver_newton_switch_tol: natural residual at which sweeps hand over to Newton */
  PetscInt   max_sweeps;           /* -solver_newton_max_sweeps: sweeps over the whole solve */
  PetscInt   sweep_check;          /* residual checked every this many sweeps */
  NewtonProx prox;                 /* -solver_prox */
  PetscReal  alpha;                /* -solver_prox_alpha: sigma / mean W_nn = alpha * natural residual */
  PetscReal  sigma_min, sigma_max; /* -solver_prox_sigma_min, _max: its bounds */
  PetscReal  alpha_min;            /* smallest alpha */
  PetscInt   inner_max;            /* -solver_prox_inner_max: Newton steps per outer iteration */
  PetscInt   stall_steps;          /* -solver_newton_stall_steps: crawling steps that end an inner Newton */
  PetscInt   redundant_max;        /* -solver_newton_redundant_max: several ranks, J gathered whole up to this many rows */
  PetscBool  user_pc;              /* -solver_pc_type given: the user chose the linear solver */
  PetscReal  inner_rtol;           /* inner tolerance on |F|, relative to the natural residual times |r| */
  PetscReal  sigma;                /* this outer iteration's sigma (0 without the proximal term) */
  PetscReal  sigma_used;           /* sigma of the Jacobian last assembled (-1: none this step) */
  PetscBool  project;              /* -solver_newton_project: line search along the path projected on the cones */
  PetscInt   reuse_its;            /* -solver_newton_reuse_its: GMRES iterations on a stale factorization (0: never); with
                                      additive Schwarz, twice the changed contacts up to which its set-up is kept */
  PetscBool configure_subs;        /* the subdomain solvers of ksp's additive Schwarz are still to be chosen */
  PetscBool sorted_subdomains;     /* their LU in the subdomain's AMD order (newton_subdomain.c), unless an option
                                      chooses the subdomain solvers or the preconditioner (NewtonChooseSortedSubdomains) */
  PetscBool smoothing;             /* -solver_newton_smoothing: smoothing Newton first (SolveSmoothed) */
  PetscReal smooth_kappa;          /* -solver_newton_smoothing_kappa: its Jacobian's regularisation / natural residual */
  PetscReal smooth_eps;            /* -solver_newton_smoothing_eps: its first eps / largest |rho v^d_n| */
  PetscInt  smooth_raises;         /* -solver_newton_smoothing_raises: stalls that raise eps instead of ending the phase */
  PetscBool smooth_raises_set;     /* given: it holds after the interior-point start too (SmoothingRaises) */
  PetscInt  smooth_raised;         /* raises of eps in the last solve's smoothing phase */
  PetscReal eps;                   /* > 0: F is the smoothed Alart-Curnier function with this eps */
  PetscInt  smooth_steps;          /* Newton steps of the last solve's smoothing phase */
  PetscReal second_rho;            /* -solver_newton_second_rho: rho factor of a second Attempt after a failed first (0: none) */
  PetscInt  second_window;         /* -solver_newton_second_window: Newton steps without a tenfold gain that end the first */
  PetscReal rho_used;              /* the factor of the current Attempt's rho */
  PetscInt  second_attempts;       /* second Attempts of the last solve (0 or 1) */
  PetscInt  desaxce_max_it;        /* -solver_newton_desaxce_max_it: De Saxce QPs before Newton (0: none) */
  PetscReal desaxce_tol;           /* -solver_newton_desaxce_tol: natural residual that ends them */
  PetscReal desaxce_qp_tol;        /* -solver_newton_desaxce_qp_tol: each QP's tolerance relative to the impulse scale */
  PetscInt  desaxce_qps;           /* the last solve's De Saxce QPs */
  PetscInt  desaxce_ip_its;        /* their interior-point iterations */
  PetscReal desaxce_seconds;       /* and their time */
  PetscInt  ip_max_it;             /* -solver_newton_ip_max_it: interior-point iterations before Newton (0: none) */
  PetscReal ip_tol;                /* -solver_newton_ip_tol: natural residual that ends them */
  PetscBool ip_tol_set;            /* given: without friction too (else -solver_tol there) */
  PetscInt  ip_its;                /* the last solve's interior-point iterations */
  PetscBool ip_answer;             /* the last solve went on from the interior point's answer (it improved on the entry) */
  PetscReal ip_seconds;            /* and their time */
  PetscBool factored;              /* ksp's preconditioner was set up on a J of this step */
  PetscBool stale;                 /* J changed since that set-up */
  /* figures of the last solve */
  PetscInt  linear_its, backtracks, failed_searches, failed_linear, sweeps, outer, jacobians, stalls, factorizations, reused;
  PetscReal linear_seconds, last_shift, merit;
  PetscReal enorm; /* |e| of the last natural residual computed (NaturalResidual) */
} Newton;

/* newton_linear.c */
PETSC_INTERN PetscErrorCode NewtonScaleRows(Mat Wpart, Mat P, PetscInt nrows, PetscInt nc, const PetscReal *A, const PetscReal *B,
                                            PetscInt stride, const PetscInt *order, const PetscInt *own, PetscReal sigma, PetscReal eps);
PETSC_INTERN PetscErrorCode NewtonLocateOwnBlocks(Mat, PetscInt nc, PetscInt *own);
PETSC_INTERN PetscErrorCode NewtonCreateLinearSolver(KergsSolver, Newton *);
PETSC_INTERN PetscErrorCode NewtonChoosePresorting(KergsSolver, Newton *);
PETSC_INTERN PetscErrorCode NewtonChooseSortedSubdomains(Newton *);
PETSC_INTERN PetscErrorCode NewtonSetUpJacobian(KergsSolver, Newton *, PetscInt n, PetscInt nc);
PETSC_INTERN PetscErrorCode NewtonAssembleJacobian(KergsSolver, Newton *, PetscInt n, PetscInt nc, PetscReal eps, PetscReal sigma);
PETSC_INTERN PetscErrorCode NewtonSolveDirection(Newton *, PetscInt n, PetscInt nc, PetscBool *solved);
PETSC_INTERN PetscErrorCode NewtonSolveSystem(Newton *, KSP, KSPConvergedReason *);
PETSC_INTERN PetscErrorCode NewtonDestroyJacobian(Newton *);
/* The local contact of J's block row i (order[i], or i when J's rows are the contacts in their own order). */
static inline PetscInt NewtonRowContact(const Newton *nt, PetscInt i) { return nt->order ? nt->order[i] : i; }
/* newton_working.c */
PETSC_INTERN PetscErrorCode NewtonWorkingSetBegin(KergsSolver, Newton *, PetscInt n, PetscInt nc, Vec r, Vec u);
PETSC_INTERN PetscErrorCode NewtonWorkingSetGrow(KergsSolver, Newton *, PetscInt n, PetscInt nc, PetscBool *grown);

/* Contact a's impulse ra and natural map e (KergsLawNaturalMap) from the arrays of r and u = W r + v^d. */
static inline void NewtonContactNaturalMap(KergsSolver s, const Newton *nt, PetscInt nc, PetscInt a, const PetscScalar rl[],
                                           const PetscScalar ul[], PetscReal ra[], PetscReal e[])
{
  PetscReal ua[KERGS_MAXCOMP];

  for (PetscInt c = 0; c < nc; c++) {
    ra[c] = PetscRealPart(rl[a * nc + c]);
    ua[c] = PetscRealPart(ul[a * nc + c]);
  }
  KergsLawNaturalMap(nc, ra, ua, s->mu[a], nt->rho_nat[a], s->active[a], e);
}

/* newton_desaxce.c */
PETSC_INTERN PetscErrorCode NewtonDeSaxceCreateTao(KergsSolver, Tao *);
PETSC_INTERN PetscErrorCode NewtonDeSaxceStart(KergsSolver, Newton *, PetscInt n, PetscInt nc, PetscReal wmean, PetscReal scale, Vec r,
                                               Vec u, Vec vd, PetscReal *res);
/* newton_ip.c */
PETSC_INTERN PetscErrorCode NewtonInteriorPointStart(KergsSolver, Newton *, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscReal *res);
PETSC_INTERN PetscErrorCode NewtonInteriorPointCreateKSP(KergsSolver, PetscInt nc, KSP *);
/* newton_residual.c */
PETSC_INTERN PetscErrorCode NewtonNaturalResidual(KergsSolver, Newton *, PetscInt n, PetscInt nc, Vec r, Vec u, PetscReal *res);
/* newton_subdomain.c */
PETSC_INTERN PetscErrorCode NewtonSubdomainSetSortedLU(PC);
PETSC_INTERN PetscErrorCode NewtonSubdomainReleaseSortedLU(PC);
PETSC_INTERN PetscErrorCode NewtonSubdomainCreateSource(Newton *, Mat W, Mat *P);
PETSC_INTERN PetscErrorCode NewtonSubdomainSetBlocks(Newton *, PetscInt nc);
PETSC_INTERN PetscErrorCode NewtonSubdomainsFromW(Newton *, PetscBool *);

#endif
