/* kergs solver type "newton": a semismooth Newton method on the Alart-Curnier function of the exact 2D law, inside
   proximal point iterations, solving the original per-step problem (not a regularised one) to tight tolerances
   (docs/solver.md, "Newton").

   Alart-Curnier function (KergsLawAlartCurnier, src/solver/law.c): per active contact, with u = W r + v^d and
   rho = -solver_newton_rho / W_aa,nn, F_n = r_n - max(0, xi), F_t = r_t - proj_[-tau, tau](r_t - rho u_t), xi = r_n - rho
   u_n, tau = mu max(0, xi); F = r for an inactive contact. F = 0 exactly when r solves the step's problem. F is
   piecewise linear, and an element of its generalized Jacobian is J = A + B W with A, B block diagonal (one ncomp x
   ncomp block per contact). W over the active contacts is stored whole (both triangles) and J is built on its pattern;
   J d = -F is solved through a KSP (prefix solver_): a direct LU by default (PETSc's; on several ranks see ChooseLinearSolver),
   any Krylov method and preconditioner by options.

   W is singular in a confined packing (its kernel: the self-equilibrated force networks), and so is J where stick
   contacts carry a hyperstatic network: plain Newton then stalls. The outer iterations solve, by Newton, the proximal
   problem with W + sigma I and v^d - sigma r_c around the current point r_c (-solver_prox identity), whose Jacobian
   J = A + B (W + sigma I) is nonsingular; at the fixed point the proximal term vanishes, so the answer solves the
   original problem. sigma = alpha * natural residual * mean W_nn (within [sigma_min, sigma_max]) follows the residual
   down, so that the convergence is fast near the solution; alpha shrinks after a solved proximal problem and grows
   tenfold after a failed one (which restarts from the centre when it made things worse). The inner Newton steps are
   damped by an Armijo line search on 1/2 |F|^2. J is assembled and factored again only when the contact states or
   sigma changed. Before the proximal iterations, unless a plain attempt from the warm start (at most 3 Newton steps,
   stopped after one that gains less than tenfold) cuts the natural residual a thousandfold, a smoothing Newton phase
   (SolveSmoothed, -solver_newton_smoothing) solves the smoothed function (KergsLawAlartCurnierSmoothed) for eps
   falling tenfold at a time, with a Levenberg-Marquardt term in J, eps raised a hundredfold at its first stall; the
   proximal iterations finish from where it ends. On one rank J is stored in W's AMD order (PresortContacts). The type is warm-started from
   the previous step's impulses like every type; optional NLGS sweeps first (-solver_newton_max_sweeps, -solver_newton_switch_tol).
   Convergence is the natural residual of the original problem (-solver_tol, default 1e-10). */
#include <kergs/private/solverimpl.h>
#include <petscksp.h>
#include <string.h>

typedef enum { NEWTON_PROX_NONE, NEWTON_PROX_IDENTITY } NewtonProx;
static const char *const NewtonProxes[] = {"none", "identity", "NewtonProx", "NEWTON_PROX_", NULL};

typedef struct {
  KSP ksp;      /* J d = -F; prefix solver_ */
  KSP kreuse;   /* J d = -F by GMRES preconditioned by the last factorization of an earlier J; prefix solver_reuse_ */
  Mat Wfull, J; /* W with both triangles, and the Jacobian on its pattern */
  /* one rank, kergs's LU: J is stored with its block rows and columns in W's AMD order, factored in that (natural)
     order (PresortContacts) */
  PetscInt  *order;   /* J's block row i is contact order[i]; NULL: J in the contacts' order */
  PetscBool  presort; /* decided once the linear solver's options are read (PresortApplies) */
  Mat        Wsorted; /* W in that order: J's template */
  Vec        Fs, ds;  /* -F and d in that order */
  Vec        F, d, Wd, rtry, utry, Ftry;
  Vec        rc, ueff;      /* the proximal centre, and the proximal problem's velocity */
  Vec        rplain;        /* the end of the plain attempt, kept while the smoothing phase runs */
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
  PetscBool smoothing;             /* -solver_newton_smoothing: smoothing Newton first (SolveSmoothed) */
  PetscReal smooth_kappa;          /* -solver_newton_smoothing_kappa: its Jacobian's regularisation / natural residual */
  PetscReal smooth_eps;            /* -solver_newton_smoothing_eps: its first eps / largest |rho v^d_n| */
  PetscInt  smooth_raises;         /* -solver_newton_smoothing_raises: stalls that raise eps instead of ending the phase */
  PetscReal eps;                   /* > 0: F is the smoothed Alart-Curnier function with this eps */
  PetscInt  smooth_steps;          /* Newton steps of the last solve's smoothing phase */
  PetscBool factored;              /* ksp's preconditioner was set up on a J of this step */
  PetscBool stale;                 /* J changed since that set-up */
  /* figures of the last solve */
  PetscInt  linear_its, backtracks, failed_searches, failed_linear, sweeps, outer, jacobians, stalls, factorizations, reused;
  PetscReal linear_seconds, last_shift, merit;
  PetscReal enorm; /* |e| of the last natural residual computed (NaturalResidual) */
} Newton;

/* ------------------------------------------------------------------------------------------------ */
/* The Alart-Curnier function over the local contacts (KergsLawAlartCurnier, src/solver/law.c)       */

/* F over the local contacts, from r and u; with the Jacobian blocks when jac. Returns 1/2 |F|^2 (global). */
static PetscErrorCode EvaluateFunction(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec F, PetscBool jac,
                                       PetscReal *merit)
{
  const PetscScalar *rl, *ul;
  PetscScalar       *Fl;
  PetscReal          sum = 0.0;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(u, &ul));
  PetscCall(VecGetArray(F, &Fl));
  for (PetscInt a = 0; a < n; a++) {
    PetscReal f[KERGS_MAXCOMP];
    if (nt->eps > 0)
      KergsLawAlartCurnierSmoothed(nc, rl + a * nc, ul + a * nc, s->mu[a], nt->rho[a], s->active[a], nt->eps, f,
                                   jac ? nt->A + a * nc * nc : NULL, jac ? nt->B + a * nc * nc : NULL);
    else
      KergsLawAlartCurnier(nc, rl + a * nc, ul + a * nc, s->mu[a], nt->rho[a], s->active[a], f, jac ? nt->A + a * nc * nc : NULL,
                           jac ? nt->B + a * nc * nc : NULL);
    for (PetscInt c = 0; c < nc; c++) {
      Fl[a * nc + c] = f[c];
      sum += f[c] * f[c];
    }
  }
  PetscCall(VecRestoreArray(F, &Fl));
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sum, 1, MPIU_REAL, MPIU_SUM, s->comm));
  *merit = 0.5 * sum;
  PetscFunctionReturn(0);
}

/* The natural residual of the original problem (KergsLawNaturalResidualScaled, docs/solver.md) from r and u = W r + v^d. */
static PetscErrorCode NaturalResidual(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, PetscReal *res)
{
  const PetscScalar *rl, *ul;
  PetscReal          sums[3] = {0.0, 0.0, 0.0};

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(u, &ul));
  for (PetscInt a = 0; a < n; a++) {
    PetscReal ra[KERGS_MAXCOMP], ua[KERGS_MAXCOMP], e[KERGS_MAXCOMP];
    for (PetscInt c = 0; c < nc; c++) {
      ra[c] = PetscRealPart(rl[a * nc + c]);
      ua[c] = PetscRealPart(ul[a * nc + c]);
    }
    KergsLawNaturalMap(nc, ra, ua, s->mu[a], nt->rho_nat[a], s->active[a], e);
    for (PetscInt c = 0; c < nc; c++) {
      sums[0] += e[c] * e[c];
      sums[1] += ra[c] * ra[c];
      sums[2] += PetscSqr(ra[c] - e[c]);
    }
  }
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 3, MPIU_REAL, MPIU_SUM, s->comm));
  *res      = KergsLawNaturalResidualScaled(sums[0], sums[1], sums[2]);
  nt->enorm = PetscSqrtReal(sums[0]);
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* The Jacobian J = A + B (W + sigma I) + eps I on W's pattern                                        */

/* The local (diagonal) part of a parallel matrix, or the matrix itself, and the off-process part (NULL on one rank). */
static PetscErrorCode GetParts(Mat M, PetscInt nc, Mat *Ad, Mat *Ao)
{
  PetscBool mpi;

  PetscFunctionBeginUser;
  *Ao = NULL;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)M, &mpi, MATMPIAIJ, MATMPIBAIJ, ""));
  if (!mpi)
    *Ad = M;
  else if (nc > 1)
    PetscCall(MatMPIBAIJGetSeqBAIJ(M, Ad, Ao, NULL));
  else
    PetscCall(MatMPIAIJGetSeqAIJ(M, Ad, Ao, NULL));
  PetscFunctionReturn(0);
}

/* Block row a of a sequential (B)AIJ part of J is B_k (nc x nc) times block row a of the same part of W (the same
   pattern, W being J's template), k the contact of that row (order[a], or a); in the diagonal part, A_k + sigma B_k +
   eps I is also added to the own block, found at diagblock[a]. BAIJ stores each block column by column: entry (c, e) at c + e nc. Reading W
   and writing J in one pass spares copying W into J first. */
static PetscErrorCode ScaleBlockRows(Newton *nt, Mat Wpart, Mat P, PetscInt n, PetscInt nc, PetscBool diagonal, PetscReal eps,
                                     PetscReal sigma)
{
  const PetscInt *ia, *ja;
  PetscInt        nrow;
  PetscBool       done;
  PetscScalar    *w, *v; /* W is only read (PETSc 3.18 has no read-only access to a BAIJ array) */

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(P, 0, PETSC_FALSE, (PetscBool)(nc > 1), &nrow, &ia, &ja, &done));
  PetscCheck(done && nrow == n, PETSC_COMM_SELF, PETSC_ERR_PLIB, "newton: cannot read the Jacobian's rows");
  if (nc > 1) {
    PetscCall(MatSeqBAIJGetArray(Wpart, &w));
    PetscCall(MatSeqBAIJGetArray(P, &v));
  } else {
    PetscCall(MatSeqAIJGetArrayRead(Wpart, (const PetscScalar **)&w));
    PetscCall(MatSeqAIJGetArray(P, &v));
  }
  for (PetscInt a = 0; a < n; a++) {
    const PetscInt   contact = nt->order ? nt->order[a] : a;
    const PetscReal *Ba = nt->B + contact * nc * nc, *Aa = nt->A + contact * nc * nc;
    for (PetscInt j = ia[a]; j < ia[a + 1]; j++) {
      const PetscScalar *wb  = w + j * nc * nc;
      PetscScalar       *out = v + j * nc * nc;
      if (nc == 2) { /* the 2D case, written out: most of the time goes here */
        out[0] = Ba[0] * wb[0] + Ba[1] * wb[1];
        out[1] = Ba[2] * wb[0] + Ba[3] * wb[1];
        out[2] = Ba[0] * wb[2] + Ba[1] * wb[3];
        out[3] = Ba[2] * wb[2] + Ba[3] * wb[3];
      } else
        for (PetscInt c = 0; c < nc; c++)
          for (PetscInt e = 0; e < nc; e++) {
            PetscScalar sum = 0.0;
            for (PetscInt k = 0; k < nc; k++) sum += Ba[c * nc + k] * wb[k + e * nc];
            out[c + e * nc] = sum;
          }
      if (diagonal && j == nt->diagblock[a])
        for (PetscInt c = 0; c < nc; c++) {
          for (PetscInt e = 0; e < nc; e++) out[c + e * nc] += Aa[c * nc + e] + sigma * Ba[c * nc + e];
          out[c + c * nc] += eps;
        }
    }
  }
  if (nc > 1) {
    PetscCall(MatSeqBAIJRestoreArray(P, &v));
    PetscCall(MatSeqBAIJRestoreArray(Wpart, &w));
  } else {
    PetscCall(MatSeqAIJRestoreArray(P, &v));
    PetscCall(MatSeqAIJRestoreArrayRead(Wpart, (const PetscScalar **)&w));
  }
  PetscCall(MatRestoreRowIJ(P, 0, PETSC_FALSE, (PetscBool)(nc > 1), &nrow, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

/* Position of each block row's own block in the diagonal part (its local block column is the row). */
static PetscErrorCode LocateDiagonalBlocks(Newton *nt, Mat Ad, PetscInt n, PetscInt nc)
{
  const PetscInt *ia, *ja;
  PetscInt        nrow;
  PetscBool       done;

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(Ad, 0, PETSC_FALSE, (PetscBool)(nc > 1), &nrow, &ia, &ja, &done));
  for (PetscInt a = 0; a < n; a++) {
    nt->diagblock[a] = -1;
    for (PetscInt j = ia[a]; j < ia[a + 1]; j++)
      if (ja[j] == a) nt->diagblock[a] = j;
    PetscCheck(nt->diagblock[a] >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "newton: W's diagonal block of local contact %" PetscInt_FMT " is not stored", a);
  }
  PetscCall(MatRestoreRowIJ(Ad, 0, PETSC_FALSE, (PetscBool)(nc > 1), &nrow, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

/* The local contacts whose Jacobian blocks (A, B) differ from A0, B0. */
static PetscInt ChangedBlocks(const Newton *nt, PetscInt n, PetscInt nc, const PetscReal *A0, const PetscReal *B0)
{
  const size_t bytes   = (size_t)nc * nc * sizeof(PetscReal);
  PetscInt     changed = 0;

  for (PetscInt a = 0; a < n; a++)
    if (memcmp(nt->A + a * nc * nc, A0 + a * nc * nc, bytes) || memcmp(nt->B + a * nc * nc, B0 + a * nc * nc, bytes)) changed++;
  return changed;
}

/* J = A + B (W + sigma I) + eps I, unless the contact states (A, B) and sigma are those of the last Jacobian: F is
   piecewise linear, so once the states settle J stays the same and its factorization is reused (the Newton step then
   costs one solve). */
static PetscErrorCode AssembleJacobian(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, PetscReal eps, PetscReal sigma)
{
  Mat      Ad, Ao, Wd, Wo;
  PetscInt changed = (PetscInt)(sigma != nt->sigma_used || ChangedBlocks(nt, n, nc, nt->Aused, nt->Bused) > 0);

  PetscFunctionBeginUser;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &changed, 1, MPIU_INT, MPI_MAX, s->comm));
  if (!changed) PetscFunctionReturn(0);
  PetscCall(PetscArraycpy(nt->Aused, nt->A, n * nc * nc));
  PetscCall(PetscArraycpy(nt->Bused, nt->B, n * nc * nc));
  nt->sigma_used = sigma;
  nt->jacobians++;
  nt->stale = PETSC_TRUE;
  PetscCall(GetParts(nt->order ? nt->Wsorted : nt->Wfull, nc, &Wd, &Wo));
  PetscCall(GetParts(nt->J, nc, &Ad, &Ao));
  PetscCall(ScaleBlockRows(nt, Wd, Ad, n, nc, PETSC_TRUE, eps, sigma));
  if (Ao) PetscCall(ScaleBlockRows(nt, Wo, Ao, n, nc, PETSC_FALSE, 0.0, 0.0));
  /* values changed through the arrays: assembling again tells PETSc (and the factorization) that J changed */
  PetscCall(MatAssemblyBegin(nt->J, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(nt->J, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Set-up and solve                                                                                 */

static PetscErrorCode EnsureWork(Newton *nt, PetscInt n)
{
  PetscFunctionBeginUser;
  if (n <= nt->nalloc) PetscFunctionReturn(0);
  PetscCall(PetscFree5(nt->A, nt->B, nt->rho, nt->rho_nat, nt->diagblock));
  PetscCall(PetscFree2(nt->Aused, nt->Bused));
  PetscCall(PetscFree2(nt->Afact, nt->Bfact));
  nt->nalloc = PetscMax(n, 2 * nt->nalloc);
  PetscCall(PetscMalloc2(nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->Afact, nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->Bfact));
  PetscCall(PetscMalloc2(nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->Aused, nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->Bused));
  PetscCall(PetscMalloc5(nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->A, nt->nalloc * KERGS_MAXCOMP * KERGS_MAXCOMP, &nt->B, nt->nalloc,
                         &nt->rho, nt->nalloc, &nt->rho_nat, nt->nalloc, &nt->diagblock));
  PetscFunctionReturn(0);
}

static PetscErrorCode DestroyStepObjects(Newton *nt)
{
  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&nt->Wfull));
  PetscCall(MatDestroy(&nt->Wsorted));
  PetscCall(PetscFree(nt->order));
  PetscCall(VecDestroy(&nt->Fs));
  PetscCall(VecDestroy(&nt->ds));
  PetscCall(MatDestroy(&nt->J));
  PetscCall(VecDestroy(&nt->F));
  PetscCall(VecDestroy(&nt->d));
  PetscCall(VecDestroy(&nt->Wd));
  PetscCall(VecDestroy(&nt->rtry));
  PetscCall(VecDestroy(&nt->utry));
  PetscCall(VecDestroy(&nt->Ftry));
  PetscCall(VecDestroy(&nt->rc));
  PetscCall(VecDestroy(&nt->ueff));
  PetscCall(VecDestroy(&nt->rplain));
  PetscFunctionReturn(0);
}

/* MUMPS's null-pivot detection (ICNTL(24) = 1): a singular J (hyperstatic stick networks) gets a solution of its
   consistent part instead of a failed factorization. Set on this step's factor before it is computed; an option
   -solver_mat_mumps_icntl_24 given by the user still wins (read at the factorization). */
static PetscErrorCode EnableNullPivots(Newton *nt)
{
  PC            pc;
  Mat           F;
  MatSolverType type;
  PetscBool     mumps;

  PetscFunctionBeginUser;
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCLU, &mumps));
  if (!mumps) PetscFunctionReturn(0);
  PetscCall(PCFactorGetMatSolverType(pc, &type));
  PetscCall(PetscStrcmp(type, MATSOLVERMUMPS, &mumps));
  if (!mumps) PetscFunctionReturn(0);
  PetscCall(PCFactorSetUpMatSolverType(pc));
  PetscCall(PCFactorGetMatrix(pc, &F));
  PetscCall(MatMumpsSetIcntl(F, 24, 1));
  PetscFunctionReturn(0);
}

/* The default linear solver on several ranks, chosen each step from J's size unless -solver_pc_type was given:
   - up to -solver_newton_redundant_max rows, J gathered whole on every rank and factored there by PETSc's LU with
     AMD (PCREDUNDANT): exact, and as fast as one rank. MUMPS spent about 12 ms in every factorization of
     confine500's J, where PETSc's LU takes well under one, and Newton factors up to 250 Jacobians a step; block
     Jacobi took about 90 GMRES iterations per Newton step there, additive Schwarz about 30 (the network of forces
     crosses the cut).
   - above, GMRES preconditioned by additive Schwarz with an overlap of one layer, one subdomain per rank factored by
     LU with AMD (ConfigureSubdomainSolvers): nothing of the size of the whole J on one rank; faster than the
     gathered LU and than block Jacobi (overlap 0) from 5,000 disks on (docs/solver.md, "Linear algebra").
   -solver_redundant_* options, read last, win; the subdomain solvers are chosen by ConfigureSubdomainSolvers. */
static PetscErrorCode ChooseLinearSolver(KergsSolver s, Newton *nt)
{
  PC          pc, subpc;
  KSP         inner;
  PetscInt    rows;
  PetscMPIInt size;

  PetscFunctionBeginUser;
  nt->configure_subs = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  if (size == 1 || nt->user_pc) PetscFunctionReturn(0);
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(MatGetSize(nt->J, &rows, NULL));
  if (rows <= nt->redundant_max) {
    PetscCall(KSPSetType(nt->ksp, KSPPREONLY));
    PetscCall(PCSetType(pc, PCREDUNDANT));
    PetscCall(PCRedundantGetKSP(pc, &inner));
    PetscCall(KSPGetPC(inner, &subpc));
    PetscCall(PCSetType(subpc, PCLU));
    PetscCall(PCFactorSetMatSolverType(subpc, MATSOLVERPETSC));
    PetscCall(PCFactorSetMatOrderingType(subpc, MATORDERINGAMD));
    PetscCall(KSPSetFromOptions(inner));
    PetscFunctionReturn(0);
  }
  PetscCall(KSPSetType(nt->ksp, KSPGMRES));
  PetscCall(KSPSetTolerances(nt->ksp, 1e-6, PETSC_DEFAULT, PETSC_DEFAULT, 200));
  PetscCall(PCSetType(pc, PCASM));
  PetscCall(PCASMSetOverlap(pc, 1));
  PetscCall(KSPSetFromOptions(nt->ksp)); /* -solver_ksp_rtol, -solver_pc_asm_overlap and the like */
  nt->configure_subs = PETSC_TRUE;       /* ConfigureSubdomainSolvers, at the first solve */
  PetscFunctionReturn(0);
}

/* The subdomain solvers of additive Schwarz exist once the KSP is set up: LU with AMD on each, chosen at the step's
   first Newton solve, once J holds its first values (set up at the step's set-up, they would first factor the
   subdomains of J's initial copy of W, singular: a wasted factorization, which fails). -solver_sub_* options, read
   last, win. */
static PetscErrorCode ConfigureSubdomainSolvers(Newton *nt)
{
  PC       pc, subpc;
  KSP     *sub;
  PetscInt nblocks;

  PetscFunctionBeginUser;
  if (!nt->configure_subs) PetscFunctionReturn(0);
  nt->configure_subs = PETSC_FALSE;
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(KSPSetUp(nt->ksp));
  PetscCall(PCASMGetSubKSP(pc, &nblocks, NULL, &sub));
  for (PetscInt b = 0; b < nblocks; b++) {
    PetscCall(KSPSetType(sub[b], KSPPREONLY));
    PetscCall(KSPGetPC(sub[b], &subpc));
    PetscCall(PCSetType(subpc, PCLU));
    PetscCall(PCFactorSetMatOrderingType(subpc, MATORDERINGAMD));
    PetscCall(KSPSetFromOptions(sub[b]));
  }
  PetscFunctionReturn(0);
}

/* On one rank, with kergs's own LU (PETSc's LU through KSPPREONLY, its ordering not chosen by
   -solver_pc_factor_mat_ordering_type, no -solver_pc_type), J is built with its block rows and columns already in
   W's AMD order and factored with the natural ordering, instead of handing PETSc's LU the AMD ordering to apply: W
   is permuted once per step (its pattern, hence the ordering, is the step's), and -F and d once per Newton step. Same
   factors, same iterates up to rounding; PETSc's kernel for a permuted 2 x 2-block matrix copies and zeroes every
   block through a library call, its natural-ordering kernel does not: 12.3 ms per factorization of pressure20k's J
   instead of 15.1. */
static PetscErrorCode PresortApplies(KergsSolver s, Newton *nt, PetscBool *applies)
{
  PetscMPIInt   size;
  PC            pc;
  KSPType       ktype;
  PCType        ptype;
  MatSolverType stype;
  PetscBool     preonly, lu, petsc, chosen;

  PetscFunctionBeginUser;
  *applies = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCall(PetscOptionsHasName(NULL, "solver_", "-pc_factor_mat_ordering_type", &chosen));
  if (size > 1 || nt->user_pc || chosen) PetscFunctionReturn(0);
  PetscCall(KSPGetType(nt->ksp, &ktype));
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(PCGetType(pc, &ptype));
  PetscCall(PCFactorGetMatSolverType(pc, &stype));
  PetscCall(PetscStrcmp(ktype, KSPPREONLY, &preonly));
  PetscCall(PetscStrcmp(ptype, PCLU, &lu));
  PetscCall(PetscStrcmp(stype, MATSOLVERPETSC, &petsc));
  *applies = (PetscBool)(preonly && lu && petsc);
  PetscFunctionReturn(0);
}

static PetscErrorCode PresortContacts(Newton *nt, PetscInt n, PetscInt nc)
{
  IS              rows, cols, points;
  const PetscInt *idx;
  PetscInt        m;

  PetscFunctionBeginUser;
  if (!nt->presort || n == 0) PetscFunctionReturn(0);
  PetscCall(MatGetOrdering(nt->Wfull, MATORDERINGAMD, &rows, &cols));
  PetscCall(ISGetLocalSize(rows, &m));
  PetscCheck(m == n, PETSC_COMM_SELF, PETSC_ERR_PLIB, "newton: W's ordering has %" PetscInt_FMT " entries for %" PetscInt_FMT " contacts",
             m, n);
  PetscCall(PetscMalloc1(n, &nt->order));
  PetscCall(ISGetIndices(rows, &idx));
  PetscCall(PetscArraycpy(nt->order, idx, n));
  PetscCall(ISCreateBlock(PETSC_COMM_SELF, nc, n, idx, PETSC_COPY_VALUES, &points));
  PetscCall(ISRestoreIndices(rows, &idx));
  PetscCall(MatPermute(nt->Wfull, points, points, &nt->Wsorted)); /* Wsorted(i, j) = W(order[i], order[j]), by blocks */
  PetscCall(ISDestroy(&points));
  PetscCall(ISDestroy(&rows));
  PetscCall(ISDestroy(&cols));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverSetUp_Newton(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  Newton        *nt = (Newton *)s->data;
  KergsDofLayout layout;
  PetscInt       n, nc;
  PetscReal     *blocks;
  Mat            Ad, Ao;
  Vec            r;

  PetscFunctionBeginUser;
  PetscCall(KergsSolverSetUpSweep(s, scene, contacts, ops)); /* active set, mu, and the residual's sweep on W */
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, NULL, NULL));
  nc = layout.ncomp;
  PetscCall(EnsureWork(nt, n));
  PetscCall(DestroyStepObjects(nt));
  PetscCall(KergsOperatorsGetFullW(ops, &nt->Wfull));
  PetscCall(PresortContacts(nt, n, nc));
  PetscCall(MatDuplicate(nt->order ? nt->Wsorted : nt->Wfull, MAT_COPY_VALUES, &nt->J));
  if (nt->order) PetscCall(MatCreateVecs(nt->J, &nt->ds, &nt->Fs));
  PetscCall(GetParts(nt->J, nc, &Ad, &Ao));
  PetscCall(LocateDiagonalBlocks(nt, Ad, n, nc));
  PetscCall(PetscMalloc1(n * nc * nc + 1, &blocks));
  PetscCall(KergsSweepGetDiagonalBlocks(s->sweep, blocks));
  for (PetscInt a = 0; a < n; a++) {
    const PetscReal wnn = blocks[a * nc * nc];
    nt->rho_nat[a]      = wnn > 0 ? 1.0 / wnn : 1.0;
    nt->rho[a]          = nt->rho_factor * nt->rho_nat[a];
  }
  PetscCall(PetscFree(blocks));
  PetscCall(VecDuplicate(r, &nt->F));
  PetscCall(VecDuplicate(r, &nt->d));
  PetscCall(VecDuplicate(r, &nt->Wd));
  PetscCall(VecDuplicate(r, &nt->rtry));
  PetscCall(VecDuplicate(r, &nt->utry));
  PetscCall(VecDuplicate(r, &nt->Ftry));
  PetscCall(VecDuplicate(r, &nt->rc));
  PetscCall(VecDuplicate(r, &nt->ueff));
  PetscCall(VecDuplicate(r, &nt->rplain));
  PetscCall(KSPReset(nt->ksp)); /* J's sizes and pattern are this step's */
  nt->sigma_used = -1.0;
  PetscCall(KSPSetOperators(nt->ksp, nt->J, nt->J));
  PetscCall(KSPReset(nt->kreuse));
  PetscCall(KSPSetOperators(nt->kreuse, nt->J, nt->J));
  nt->factored = nt->stale = PETSC_FALSE;
  PetscCall(ChooseLinearSolver(s, nt));
  PetscCall(EnableNullPivots(nt));
  PetscFunctionReturn(0);
}

/* The preconditioner of the reuse solver: the factorization (or block factorizations) last computed by ksp, applied to
   a J that has changed since. Reuse is set on ksp's PC so that applying it does not factor again. */
static PetscErrorCode ApplyStaleFactor(PC pc, Vec x, Vec y)
{
  Newton *nt;
  PC      main;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &nt));
  PetscCall(KSPGetPC(nt->ksp, &main));
  PetscCall(PCSetReusePreconditioner(main, PETSC_TRUE));
  PetscCall(PCApply(main, x, y));
  PetscFunctionReturn(0);
}

/* d = J^-1 (-F) by `ksp`, counting its iterations. */
static PetscErrorCode SolveNewtonSystem(Newton *nt, KSP ksp, KSPConvergedReason *reason)
{
  PetscInt its;

  PetscFunctionBeginUser;
  if (nt->order) { /* J in W's AMD order (PresortContacts): -F into that order, d back from it */
    PetscInt           n, nc;
    const PetscScalar *f, *xs;
    PetscScalar       *bs, *x;

    PetscCall(VecGetLocalSize(nt->F, &n));
    PetscCall(MatGetBlockSize(nt->J, &nc)); /* components per contact */
    n /= nc;
    PetscCall(VecGetArrayRead(nt->F, &f));
    PetscCall(VecGetArray(nt->Fs, &bs));
    for (PetscInt i = 0; i < n; i++)
      for (PetscInt c = 0; c < nc; c++) bs[i * nc + c] = -f[nt->order[i] * nc + c];
    PetscCall(VecRestoreArray(nt->Fs, &bs));
    PetscCall(VecRestoreArrayRead(nt->F, &f));
    PetscCall(KSPSolve(ksp, nt->Fs, nt->ds));
    PetscCall(VecGetArrayRead(nt->ds, &xs));
    PetscCall(VecGetArray(nt->d, &x));
    for (PetscInt i = 0; i < n; i++)
      for (PetscInt c = 0; c < nc; c++) x[nt->order[i] * nc + c] = xs[i * nc + c];
    PetscCall(VecRestoreArray(nt->d, &x));
    PetscCall(VecRestoreArrayRead(nt->ds, &xs));
  } else {
    PetscCall(VecScale(nt->F, -1.0));
    PetscCall(KSPSolve(ksp, nt->F, nt->d));
    PetscCall(VecScale(nt->F, -1.0));
  }
  PetscCall(KSPGetConvergedReason(ksp, reason));
  PetscCall(KSPGetIterationNumber(ksp, &its));
  nt->linear_its += its;
  PetscFunctionReturn(0);
}

/* J d = -F with the factorization of an earlier J of this step. With sigma unchanged, J changes between Newton steps
   only in the rows of the contacts that changed piece: a low-rank change, which GMRES absorbs in about one iteration
   per changed row, each costing one triangular solve where a factorization costs far more. When ksp solves directly
   (KSPPREONLY: LU, or LU gathered by PCREDUNDANT), by at most -solver_newton_reuse_its GMRES iterations preconditioned
   by that factorization (kreuse); when ksp is kergs's GMRES with additive Schwarz (several ranks), by ksp with its
   preconditioner kept, to ksp's own tolerance (a Krylov method chosen by option sets up every changed J). Tried only
   when few contacts changed. *solved is false when it did not converge: then J is factored again. */
static PetscErrorCode ReuseDirection(Newton *nt, PetscInt n, PetscInt nc, PetscBool *solved)
{
  KSPConvergedReason reason;
  PetscInt           changed;
  PetscBool          direct;
  PC                 pc;

  PetscFunctionBeginUser;
  *solved = PETSC_FALSE;
  if (nt->reuse_its <= 0 || !nt->factored || !nt->stale || nt->sigma_used != nt->sigma_fact) PetscFunctionReturn(0);
  /* GMRES needs about one iteration per changed block row: try only when few changed */
  changed = ChangedBlocks(nt, n, nc, nt->Afact, nt->Bfact);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &changed, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)nt->ksp)));
  if (2 * changed > nt->reuse_its) PetscFunctionReturn(0);
  PetscCall(PetscObjectTypeCompare((PetscObject)nt->ksp, KSPPREONLY, &direct));
  if (direct)
    PetscCall(SolveNewtonSystem(nt, nt->kreuse, &reason));
  else {
    PetscBool schwarz;
    PetscCall(KSPGetPC(nt->ksp, &pc));
    PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCASM, &schwarz));
    if (!schwarz || nt->user_pc) PetscFunctionReturn(0); /* a Krylov method chosen by option: every changed J is set up */
    PetscCall(PCSetReusePreconditioner(pc, PETSC_TRUE));
    PetscCall(PCSetFailedReason(pc, PC_NOERROR));
    PetscCall(SolveNewtonSystem(nt, nt->ksp, &reason));
  }
  *solved = (PetscBool)(reason > 0);
  if (*solved) nt->reused++;
  PetscFunctionReturn(0);
}

/* Solve J d = -F: with the last factorization while it serves (ReuseDirection), else by ksp, which factors J again. A
   failed solve (a Krylov method on an ill-conditioned J, a singular factorization) is not an error: the inner Newton
   stops and the outer iteration retries with a larger proximal term, which conditions J better. */
static PetscErrorCode NewtonDirection(Newton *nt, PetscInt n, PetscInt nc, PetscBool *solved)
{
  KSPConvergedReason reason;
  PetscLogDouble     t0, t1;
  PC                 pc;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&t0));
  PetscCall(ReuseDirection(nt, n, nc, solved));
  if (!*solved) {
    PetscCall(KSPGetPC(nt->ksp, &pc));
    PetscCall(PCSetReusePreconditioner(pc, PETSC_FALSE));
    /* additive Schwarz keeps a subdomain's failed factorization as its own failure through later set-ups (PETSc
       3.18): without this, one failed solve would fail every later one, however good J */
    PetscCall(PCSetFailedReason(pc, PC_NOERROR));
    if (nt->stale || !nt->factored) nt->factorizations++;
    PetscCall(ConfigureSubdomainSolvers(nt));
    PetscCall(SolveNewtonSystem(nt, nt->ksp, &reason));
    nt->factored   = PETSC_TRUE;
    nt->stale      = PETSC_FALSE;
    nt->sigma_fact = nt->sigma_used;
    PetscCall(PetscArraycpy(nt->Afact, nt->Aused, n * nc * nc));
    PetscCall(PetscArraycpy(nt->Bfact, nt->Bused, n * nc * nc));
    *solved = (PetscBool)(reason >= 0);
    if (!*solved) {
      nt->failed_linear++;
      PetscCall(PetscInfo(NULL, "newton: the linear solve of a Newton step failed (%s): a larger proximal term next\n",
                          KSPConvergedReasons[reason]));
    }
  }
  PetscCall(PetscTime(&t1));
  nt->linear_seconds += t1 - t0;
  PetscFunctionReturn(0);
}

/* The velocity of the problem solved by the inner iterations: with the proximal term, (W + sigma I) r + v^d - sigma r_c,
   i.e. u + sigma (r - r_c) with u = W r + v^d. */
static PetscErrorCode ProximalVelocity(Newton *nt, Vec r, Vec u, Vec ueff)
{
  PetscFunctionBeginUser;
  PetscCall(VecCopy(u, ueff));
  if (nt->sigma > 0) {
    PetscCall(VecAXPY(ueff, nt->sigma, r));
    PetscCall(VecAXPY(ueff, -nt->sigma, nt->rc));
  }
  PetscFunctionReturn(0);
}

/* r <- its projection on the Coulomb cones of the active contacts (r_n >= 0, |r_t| <= mu r_n); inactive ones to 0. */
static PetscErrorCode ProjectOnCones(KergsSolver s, PetscInt n, PetscInt nc, Vec r)
{
  PetscScalar *rl;

  PetscFunctionBeginUser;
  PetscCall(VecGetArray(r, &rl));
  for (PetscInt a = 0; a < n; a++) {
    PetscScalar *ra = rl + a * nc;
    if (!s->active[a]) {
      for (PetscInt c = 0; c < nc; c++) ra[c] = 0.0;
      continue;
    }
    if (nc == 1) {
      ra[0] = PetscMax(PetscRealPart(ra[0]), 0.0);
      continue;
    }
    {
      const PetscReal mu = s->mu[a], rn = PetscRealPart(ra[0]), rt = PetscRealPart(ra[1]), at = PetscAbsReal(rt);
      if (rn >= 0 && at <= mu * rn) continue;
      if (mu * at <= -rn)
        ra[0] = ra[1] = 0.0;
      else {
        const PetscReal pn = (rn + mu * at) / (1.0 + mu * mu);
        ra[0]              = pn;
        ra[1]              = rt >= 0 ? mu * pn : -mu * pn;
      }
    }
  }
  PetscCall(VecRestoreArray(r, &rl));
  PetscFunctionReturn(0);
}

/* Backtracking: the largest t = 2^-k (k <= -solver_newton_max_backtracks) with merit(r + t d) <= (1 - 2 armijo t)
   merit(r). Without such a t the smallest step is taken anyway and *ok is false: where a contact sits exactly on a
   kink of F (a grazing contact with r = 0 and u_n = 0, plenty after NLGS sweeps), the Newton direction need not
   decrease the merit, but a tiny step moves the contact off the kink and the next Jacobian is right. On exit r, u
   hold the new point. */
static PetscErrorCode LineSearch(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscReal *merit, PetscBool *ok)
{
  PetscReal t = 1.0, trial = 0.0;
  PetscInt  k;

  PetscFunctionBeginUser;
  if (!nt->project) PetscCall(MatMult(nt->Wfull, nt->d, nt->Wd));
  for (k = 0;; k++) {
    PetscCall(VecWAXPY(nt->rtry, t, nt->d, r));
    if (nt->project) { /* along the projected path r(t) = P_K(r + t d) */
      PetscCall(ProjectOnCones(s, n, nc, nt->rtry));
      PetscCall(MatMultAdd(nt->Wfull, nt->rtry, vd, nt->utry));
    } else
      PetscCall(VecWAXPY(nt->utry, t, nt->Wd, u));
    PetscCall(ProximalVelocity(nt, nt->rtry, nt->utry, nt->ueff));
    PetscCall(EvaluateFunction(s, nt, n, nc, nt->rtry, nt->ueff, nt->Ftry, PETSC_FALSE, &trial));
    if (trial <= (1.0 - 2.0 * nt->armijo * t) * *merit || k == nt->max_backtracks) break;
    t *= 0.5;
  }
  *ok = (PetscBool)(trial <= (1.0 - 2.0 * nt->armijo * t) * *merit);
  nt->backtracks += k;
  if (!*ok) nt->failed_searches++;
  PetscCall(VecCopy(nt->rtry, r));
  PetscCall(VecCopy(nt->utry, u));
  *merit = trial;
  PetscFunctionReturn(0);
}

/* r <- x and u = W r + v^d: a point the iterations move (back) to. */
static PetscErrorCode MoveTo(Newton *nt, Vec x, Vec r, Vec u, Vec vd)
{
  PetscFunctionBeginUser;
  PetscCall(VecCopy(x, r));
  PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
  PetscFunctionReturn(0);
}

/* At most `count` NLGS sweeps on W (the sweep of KergsSolverSetUpSweep), stopping early once the natural residual is
   at most `target`; u = W r + v^d and the residual on exit. */
static PetscErrorCode Sweeps(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscInt count, PetscReal target,
                             PetscReal *res)
{
  KergsSweepMeasures m;

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < count; k++) {
    PetscCall(KergsSweepRun(s->sweep, r, vd, NULL, NULL, &m));
    nt->sweeps++;
    if ((k + 1) % nt->sweep_check == 0 && k + 1 < count) {
      PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
      PetscCall(NaturalResidual(s, nt, n, nc, r, u, res));
      if (*res <= target) break;
    }
  }
  PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
  PetscCall(NaturalResidual(s, nt, n, nc, r, u, res));
  PetscFunctionReturn(0);
}

/* The monitors' line of a Newton step: the criterion of this type is the natural residual of the original problem,
   computed here only when a monitor is set (u = W r + v^d after the line search). */
static PetscErrorCode MonitorNewtonStep(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, PetscInt step)
{
  PetscReal res;

  PetscFunctionBeginUser;
  if (!s->nmonitors) PetscFunctionReturn(0);
  PetscCall(NaturalResidual(s, nt, n, nc, r, u, &res));
  PetscCall(KergsSolverMonitor(s, step, res, res));
  PetscFunctionReturn(0);
}

/* Newton on the current (proximal) problem, from r: at most `count` steps, until |F| is at most `ftol`; *ok is false
   when some line search failed. Newton stops early when it crawls: -solver_newton_stall_steps steps in a row that
   each cut the merit by less than a tenth (many contacts change piece at every step, and the line search keeps
   them short); a larger proximal term is then cheaper than more steps. A `trial` (the plain attempt before the
   smoothing phase) also stops after a step that cut |F| by less than tenfold: the warm start is then not on the
   solution's piece, and the smoothing phase starts again from the warm start. */
static PetscErrorCode InnerNewton(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec r, Vec u, Vec vd, PetscInt count, PetscReal ftol,
                                  PetscBool trial, PetscInt *steps, PetscBool *ok)
{
  PetscReal merit;
  PetscBool decreased = PETSC_TRUE, solved, off_piece = PETSC_FALSE;
  PetscInt  crawling = 0;

  PetscFunctionBeginUser;
  *ok = PETSC_TRUE;
  PetscCall(ProximalVelocity(nt, r, u, nt->ueff));
  PetscCall(EvaluateFunction(s, nt, n, nc, r, nt->ueff, nt->F, PETSC_TRUE, &merit));
  for (PetscInt k = 0; k < count && PetscSqrtReal(2.0 * merit) > ftol; k++) {
    PetscCall(AssembleJacobian(s, nt, n, nc, nt->shift, nt->sigma));
    PetscCall(NewtonDirection(nt, n, nc, &solved));
    if (!solved) {
      *ok   = PETSC_FALSE;
      merit = PETSC_MAX_REAL; /* not solved */
      break;
    }
    {
      PetscReal m0 = merit;
      PetscInt  b0 = nt->backtracks;
      PetscCall(LineSearch(s, nt, n, nc, r, u, vd, &merit, &decreased));
      PetscCall(PetscInfo(NULL, "inner %" PetscInt_FMT ": merit %g -> %g, %" PetscInt_FMT " halvings, decreased %d, sigma %g\n", k,
                          (double)m0, (double)merit, nt->backtracks - b0, (int)decreased, (double)nt->sigma));
      crawling  = merit > 0.81 * m0 ? crawling + 1 : 0;    /* |F| down by less than a tenth */
      off_piece = (PetscBool)(trial && merit > 0.01 * m0); /* |F| down by less than tenfold */
    }
    (*steps)++;
    PetscCall(MonitorNewtonStep(s, nt, n, nc, r, u, *steps));
    if (!decreased) *ok = PETSC_FALSE;
    if (off_piece) {
      *ok = PETSC_FALSE;
      break;
    }
    if (nt->stall_steps > 0 && crawling >= nt->stall_steps) {
      *ok = PETSC_FALSE;
      nt->stalls++;
      PetscCall(ProximalVelocity(nt, r, u, nt->ueff));
      PetscCall(EvaluateFunction(s, nt, n, nc, r, nt->ueff, nt->F, PETSC_FALSE, &merit));
      break;
    }
    PetscCall(ProximalVelocity(nt, r, u, nt->ueff));
    PetscCall(EvaluateFunction(s, nt, n, nc, r, nt->ueff, nt->F, PETSC_TRUE, &merit)); /* the Jacobian blocks at the new point */
  }
  nt->merit = merit;
  PetscFunctionReturn(0);
}

/* Mean W_nn over the active contacts: the scale of the proximal term. */
static PetscErrorCode MeanCompliance(KergsSolver s, Newton *nt, PetscInt n, PetscReal *mean)
{
  PetscReal sums[2] = {0.0, 0.0};

  PetscFunctionBeginUser;
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a]) {
      sums[0] += 1.0 / nt->rho_nat[a];
      sums[1] += 1.0;
    }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 2, MPIU_REAL, MPIU_SUM, s->comm));
  *mean = sums[1] > 0 ? sums[0] / sums[1] : 1.0;
  PetscFunctionReturn(0);
}

/* The largest |rho_a v^d_n,a| over the active contacts: the scale of an impulse, for the first eps. */
static PetscErrorCode ImpulseScale(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, Vec vd, PetscReal *scale)
{
  const PetscScalar *v;

  PetscFunctionBeginUser;
  *scale = 0.0;
  PetscCall(VecGetArrayRead(vd, &v));
  for (PetscInt a = 0; a < n; a++)
    if (s->active[a]) *scale = PetscMax(*scale, PetscAbsReal(nt->rho[a] * PetscRealPart(v[a * nc])));
  PetscCall(VecRestoreArrayRead(vd, &v));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, scale, 1, MPIU_REAL, MPIU_MAX, s->comm));
  PetscFunctionReturn(0);
}

/* Smoothing Newton (-solver_newton_smoothing): Newton steps on the smoothed function F_eps (KergsLawAlartCurnierSmoothed),
   eps divided by 10 whenever F_eps is solved to a tenth of eps per component, each step damped by the Armijo line
   search on 1/2 |F_eps|^2. The first eps is -solver_newton_smoothing_eps times `scale` (ImpulseScale), at most ten
   times the start's |F| per component (a good start keeps a small eps); the last, 1e-12 of the first before that cap.
   The smoothing
   keeps J = A + B W nonsingular away from eps = 0 except on W's kernel where B is that of a stick contact; J's W part is
   regularised by sigma = kappa * natural residual * mean W_nn (within sigma_max; a Levenberg-Marquardt term: F keeps W,
   so the limit solves the original problem). Stops at the tolerance, at max_it, on a failed linear solve, or after
   -solver_newton_stall_steps steps in a row at one eps that each cut |F_eps| by less than a tenth (J nearly singular
   as eps -> 0): the proximal iterations go on from there. The first such stall of a solve (up to
   -solver_newton_smoothing_raises of them) instead raises eps a hundredfold and goes on from the current point: eps was
   lowered too early, while a few contacts were still far from their piece (on pressure20k's cold first step, two
   contacts closing at 5e-4 m/s with r_n = 0 held the residual at 1e-3), and the smoother function lets them move. */
static PetscErrorCode SolveSmoothed(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, PetscInt nglobal, Vec r, Vec u, Vec vd,
                                    PetscReal wmean, PetscReal scale, PetscInt *steps, PetscReal *res)
{
  PetscReal merit, m0, epsmin;
  PetscInt  stalls = 0, raises = 0;
  PetscBool ok, solved;

  PetscFunctionBeginUser;
  nt->sigma = 0.0; /* F without a proximal term (ProximalVelocity: u itself) */
  PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_FALSE, &merit));
  nt->eps = PetscMin(nt->smooth_eps * scale, 10.0 * PetscSqrtReal(2.0 * merit / (PetscReal)nglobal));
  epsmin  = 1e-12 * nt->smooth_eps * scale;
  while (*res > s->tol && *steps < s->max_it && nt->eps > 0) {
    const PetscInt b0 = nt->backtracks;
    PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_TRUE, &merit));
    while (PetscSqrtReal(2.0 * merit) <= 0.1 * nt->eps * PetscSqrtReal((PetscReal)nglobal) && nt->eps > epsmin) {
      nt->eps *= 0.1;
      stalls = 0;
      PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_TRUE, &merit));
    }
    m0 = merit;
    PetscCall(AssembleJacobian(s, nt, n, nc, nt->shift, PetscMin(nt->smooth_kappa * *res, nt->sigma_max) * wmean));
    PetscCall(NewtonDirection(nt, n, nc, &solved));
    if (!solved) break;
    PetscCall(LineSearch(s, nt, n, nc, r, u, vd, &merit, &ok));
    (*steps)++;
    nt->smooth_steps++;
    PetscCall(NaturalResidual(s, nt, n, nc, r, u, res));
    PetscCall(MonitorNewtonStep(s, nt, n, nc, r, u, *steps));
    PetscCall(PetscInfo(NULL, "smoothing %" PetscInt_FMT ": natural residual %g, eps %g, %" PetscInt_FMT " halvings\n", *steps,
                        (double)*res, (double)nt->eps, nt->backtracks - b0));
    stalls = merit > 0.81 * m0 ? stalls + 1 : 0; /* |F_eps| down by less than a tenth */
    if (nt->stall_steps > 0 && stalls >= nt->stall_steps) {
      if (raises == nt->smooth_raises) break;
      raises++;
      stalls = 0;
      nt->eps *= 100.0;
      PetscCall(PetscInfo(NULL, "smoothing stalled: eps raised to %g\n", (double)nt->eps));
    }
  }
  nt->eps = 0.0;
  PetscCall(EvaluateFunction(s, nt, n, nc, r, u, nt->F, PETSC_FALSE, &nt->merit)); /* the exact law's merit, for the statistics */
  PetscFunctionReturn(0);
}

/* Optional NLGS sweeps first (-solver_newton_max_sweeps), until the natural residual is at most
   -solver_newton_switch_tol. Then outer iterations: each solves, by at most -solver_prox_inner_max Newton steps, the
   proximal problem with W + sigma I and v^d - sigma r_c around the current r_c = r, and moves r_c to its solution. The
   proximal term makes every inner Jacobian nonsingular (without it, -solver_prox none, J is singular where stick
   contacts carry a hyperstatic network); at the fixed point it vanishes, so r solves the original problem. The first
   outer iteration is plain Newton (sigma_min), kept only if it lowered the natural residual. -solver_max_it caps the
   Newton steps. */
static PetscErrorCode SolverSolve_Newton(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops,
                                         KergsSolveStats *stats)
{
  Newton        *nt = (Newton *)s->data;
  KergsDofLayout layout;
  PetscInt       n, nglobal, nc, steps = 0;
  PetscReal      res = 0.0, rmax, wmean = 1.0, alpha = nt->alpha;
  PetscLogDouble t0, t1;
  PetscBool      ok, smoothing;
  Vec            r, u, vd;

  PetscFunctionBeginUser;
  (void)scene;
  PetscCall(PetscTime(&t0));
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetContactVectors(ops, &r, &u, &vd));
  PetscCall(VecGetSize(r, &nglobal));
  nc             = layout.ncomp;
  nt->linear_its = nt->backtracks = nt->failed_searches = nt->failed_linear = 0;
  nt->sweeps = nt->outer = nt->jacobians = nt->stalls = nt->factorizations = nt->reused = 0;
  nt->linear_seconds = nt->sigma = nt->merit = 0.0;
  PetscCall(MeanCompliance(s, nt, n, &wmean));
  PetscCall(VecNorm(r, NORM_INFINITY, &rmax));
  PetscCall(Sweeps(s, nt, n, nc, r, u, vd, 0, 0.0, &res));
  if (res > nt->switch_tol && nt->max_sweeps > 0) PetscCall(Sweeps(s, nt, n, nc, r, u, vd, nt->max_sweeps, nt->switch_tol, &res));
  nt->smooth_steps = 0;
  smoothing        = (PetscBool)(nt->smoothing && nt->prox == NEWTON_PROX_IDENTITY); /* the phase hands over to the proximal iterations */
  while (res > s->tol && nglobal > 0 && steps < s->max_it) {
    PetscReal before = res, inner_tol;
    PetscCall(VecCopy(r, nt->rc));
    PetscCall(NaturalResidual(s, nt, n, nc, r, u, &res)); /* |e| at the centre (after a rejected outer iteration too) */
    /* the first attempt is plain Newton (the smallest sigma): enough when the warm start lies on the solution's piece
       of F, and the residual (absolute at r = 0) says little about the distance to the solution */
    nt->sigma = nt->prox == NEWTON_PROX_IDENTITY
                    ? (nt->outer == 0 ? nt->sigma_min : PetscClipInterval(alpha * res, nt->sigma_min, nt->sigma_max)) * wmean
                    : 0.0;
    /* |F| scales with rho where the natural residual's map uses 1 / W_nn: a smaller rho asks for a smaller |F| */
    inner_tol = nt->inner_rtol * PetscMin(1.0, nt->rho_factor) * nt->enorm;
    {
      const PetscInt before_steps = steps;
      /* with smoothing, the plain attempt gets 3 Newton steps: enough on the solution's piece (a few contacts); it
         stops after one that gained less than tenfold, as little as possible lost otherwise */
      const PetscBool plain = (PetscBool)(nt->outer == 0 && smoothing);
      PetscCall(InnerNewton(s, nt, n, nc, r, u, vd, PetscMin(plain ? 3 : nt->inner_max, s->max_it - steps), inner_tol, plain, &steps, &ok));
      if (steps == before_steps) { /* an outer iteration without a Newton step still counts: the loop ends */
        steps++;
        PetscCall(MonitorNewtonStep(s, nt, n, nc, r, u, steps));
      }
    }
    PetscCall(NaturalResidual(s, nt, n, nc, r, u, &res));
    nt->outer++;
    ok = (PetscBool)(PetscSqrtReal(2.0 * nt->merit) <= inner_tol); /* the proximal problem was solved */
    if (nt->outer == 1 && nt->prox == NEWTON_PROX_IDENTITY && res >= before) {
      /* plain Newton from the warm start went elsewhere (along W's near-kernel, where sigma_min barely holds it): back */
      PetscCall(MoveTo(nt, nt->rc, r, u, vd));
      res = before;
    } else if (ok)
      alpha = res < before ? PetscMax(alpha / 3.0, nt->alpha_min) : alpha; /* a proximal step: always taken */
    else if (res < 0.9 * before)
      alpha *= 10.0; /* progress, but the proximal problem was not solved: more damping */
    else {           /* no progress: more damping, from the centre */
      alpha *= 10.0;
      if (res >= before) {
        PetscCall(MoveTo(nt, nt->rc, r, u, vd));
        res = before;
      }
    }
    PetscCall(PetscInfo(NULL,
                        "outer %" PetscInt_FMT " (%" PetscInt_FMT " Newton steps): natural residual %g -> %g, inner solved %d, alpha %g\n",
                        nt->outer, steps, (double)before, (double)res, (int)ok, (double)alpha));
    /* unless plain Newton gained three orders of magnitude (it is then on the solution's piece, where the proximal
       iterations finish in a few steps), smoothing Newton from the warm start, then the proximal iterations if needed */
    if (nt->outer == 1 && smoothing && res > 1e-3 * before && res > s->tol && steps < s->max_it) {
      PetscReal scale, plain_res = res, start_res = before; /* before: the natural residual at the warm start, nt->rc */
      PetscCall(ImpulseScale(s, nt, n, nc, vd, &scale));
      if (scale > 0) {
        PetscCall(VecCopy(r, nt->rplain));
        PetscCall(MoveTo(nt, nt->rc, r, u, vd));
        res = start_res;
        PetscCall(SolveSmoothed(s, nt, n, nc, nglobal, r, u, vd, wmean, scale, &steps, &res));
        /* the proximal iterations go on from the best of the warm start, the plain attempt's end and the smoothing's */
        if (PetscMin(start_res, plain_res) < res) {
          PetscCall(MoveTo(nt, start_res <= plain_res ? nt->rc : nt->rplain, r, u, vd));
          res = PetscMin(start_res, plain_res);
        }
        alpha = nt->alpha; /* the plain attempt's outcome says nothing about the proximal problems from here */
      }
    }
  }
  stats->iterations    = steps;
  stats->criterion     = res;
  stats->criterion_met = (PetscBool)(res <= s->tol || nglobal == 0);
  PetscCall(PetscTime(&t1));
  stats->sweep_seconds = t1 - t0;
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverStats_Newton(KergsSolver s, KergsSolveStats *st)
{
  Newton *nt = (Newton *)s->data;

  PetscFunctionBeginUser;
  PetscCall(KergsSolveStatsAdd(st, "linear_iterations", (PetscReal)nt->linear_its));
  PetscCall(KergsSolveStatsAdd(st, "linear_seconds", nt->linear_seconds));
  PetscCall(KergsSolveStatsAdd(st, "backtracks", (PetscReal)nt->backtracks));
  PetscCall(KergsSolveStatsAdd(st, "failed_line_searches", (PetscReal)nt->failed_searches));
  PetscCall(KergsSolveStatsAdd(st, "failed_linear_solves", (PetscReal)nt->failed_linear));
  PetscCall(KergsSolveStatsAdd(st, "newton_merit", nt->merit));
  PetscCall(KergsSolveStatsAdd(st, "sweeps", (PetscReal)nt->sweeps));
  PetscCall(KergsSolveStatsAdd(st, "outer_iterations", (PetscReal)nt->outer));
  PetscCall(KergsSolveStatsAdd(st, "jacobians", (PetscReal)nt->jacobians));
  PetscCall(KergsSolveStatsAdd(st, "factorizations", (PetscReal)nt->factorizations));
  PetscCall(KergsSolveStatsAdd(st, "reused_factorizations", (PetscReal)nt->reused));
  PetscCall(KergsSolveStatsAdd(st, "stalled_inner", (PetscReal)nt->stalls));
  PetscCall(KergsSolveStatsAdd(st, "smoothing_steps", (PetscReal)nt->smooth_steps));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverSetFromOptions_Newton(PetscOptionItems *PetscOptionsObject, KergsSolver s)
{
  Newton *nt = (Newton *)s->data;

  PetscFunctionBeginUser;
  PetscOptionsHeadBegin(PetscOptionsObject, "Semismooth Newton on the Alart-Curnier formulation (newton)");
  PetscCall(PetscOptionsReal("-solver_newton_rho", "Augmentation parameter rho = factor / W_aa,nn of each contact", "", nt->rho_factor,
                             &nt->rho_factor, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_shift",
                             "Shift eps of the Jacobian, J + eps I (J has entries of order 1): makes the Newton step defined where stick "
                             "contacts carry a hyperstatic network",
                             "", nt->shift, &nt->shift, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_armijo", "Sufficient decrease of the merit 1/2 |F|^2 in the line search", "", nt->armijo,
                             &nt->armijo, NULL));
  PetscCall(PetscOptionsInt("-solver_newton_max_backtracks", "Halvings of a Newton step before the smallest one is taken anyway", "",
                            nt->max_backtracks, &nt->max_backtracks, NULL));
  PetscCall(PetscOptionsBool("-solver_newton_project", "Line search along the path projected on the Coulomb cones", "", nt->project,
                             &nt->project, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_switch_tol", "NLGS sweeps first, until the natural residual is at most this, then Newton", "",
                             nt->switch_tol, &nt->switch_tol, NULL));
  PetscCall(PetscOptionsEnum("-solver_prox", "Proximal term of the outer iterations: identity (W + sigma I), none (plain Newton)", "",
                             NewtonProxes, (PetscEnum)nt->prox, (PetscEnum *)&nt->prox, NULL));
  PetscCall(PetscOptionsReal("-solver_prox_alpha", "sigma of the proximal term W + sigma I: alpha * natural residual * mean W_nn", "",
                             nt->alpha, &nt->alpha, NULL));
  PetscCall(PetscOptionsReal("-solver_prox_sigma_min", "Smallest sigma / mean W_nn", "", nt->sigma_min, &nt->sigma_min, NULL));
  PetscCall(PetscOptionsReal("-solver_prox_sigma_max", "Largest sigma / mean W_nn", "", nt->sigma_max, &nt->sigma_max, NULL));
  PetscCall(PetscOptionsInt("-solver_prox_inner_max", "Newton steps per outer iteration", "", nt->inner_max, &nt->inner_max, NULL));
  PetscCall(
      PetscOptionsInt("-solver_newton_redundant_max",
                      "Several ranks: J gathered whole on every rank and factored there up to this many rows, else GMRES with additive "
                      "Schwarz (overlap 1)",
                      "", nt->redundant_max, &nt->redundant_max, NULL));
  PetscCall(PetscOptionsHasName(NULL, "solver_", "-pc_type", &nt->user_pc));
  PetscCall(PetscOptionsInt("-solver_newton_reuse_its",
                            "GMRES iterations (relative tolerance 1e-8) preconditioned by the last factorization of J before J is factored "
                            "again, tried when at most half as many contacts changed piece (with additive Schwarz on several ranks: its "
                            "set-up kept under the same rule) (0: factor every changed J)",
                            "", nt->reuse_its, &nt->reuse_its, NULL));
  PetscCall(PetscOptionsInt("-solver_newton_stall_steps",
                            "Newton steps in a row that each cut |F| by less than a tenth and end an outer iteration's Newton (0: never)",
                            "", nt->stall_steps, &nt->stall_steps, NULL));
  PetscCall(PetscOptionsBool("-solver_newton_smoothing", "Smoothing Newton steps first, then the proximal iterations if still needed", "",
                             nt->smoothing, &nt->smoothing, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_smoothing_kappa", "Smoothing Newton: sigma of its Jacobian / (natural residual * mean W_nn)",
                             "", nt->smooth_kappa, &nt->smooth_kappa, NULL));
  PetscCall(PetscOptionsReal("-solver_newton_smoothing_eps", "Smoothing Newton: first eps / largest |rho v^d_n|", "", nt->smooth_eps,
                             &nt->smooth_eps, NULL));
  PetscCall(PetscOptionsInt("-solver_newton_smoothing_raises",
                            "Smoothing Newton: stalls of a solve that raise eps a hundredfold instead of ending the phase", "",
                            nt->smooth_raises, &nt->smooth_raises, NULL));
  PetscCall(PetscOptionsInt("-solver_newton_max_sweeps", "NLGS sweeps before Newton, at most (0: none), until -solver_newton_switch_tol",
                            "", nt->max_sweeps, &nt->max_sweeps, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(nt->alpha > 0 && PetscIsNormalReal(nt->alpha), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_prox_alpha %g must be positive",
             (double)nt->alpha);
  PetscCheck(nt->sigma_min > 0 && nt->sigma_min <= nt->sigma_max && PetscIsNormalReal(nt->sigma_max), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_prox_sigma_min %g and -solver_prox_sigma_max %g must satisfy 0 < min <= max", (double)nt->sigma_min,
             (double)nt->sigma_max);
  PetscCheck(nt->inner_max >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_prox_inner_max %" PetscInt_FMT " must be at least 1",
             nt->inner_max);
  PetscCheck(nt->redundant_max >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_redundant_max %" PetscInt_FMT " must be non-negative", nt->redundant_max);
  PetscCheck(nt->reuse_its >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_reuse_its %" PetscInt_FMT " must be non-negative",
             nt->reuse_its);
  PetscCheck(nt->stall_steps >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_stall_steps %" PetscInt_FMT " must be non-negative",
             nt->stall_steps);
  PetscCheck(nt->smooth_raises >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_smoothing_raises %" PetscInt_FMT " must be non-negative", nt->smooth_raises);
  PetscCheck(nt->max_sweeps >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_max_sweeps %" PetscInt_FMT " must be non-negative",
             nt->max_sweeps);
  PetscCheck(nt->smooth_kappa >= 0 && !PetscIsInfOrNanReal(nt->smooth_kappa), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_smoothing_kappa %g must be non-negative", (double)nt->smooth_kappa);
  PetscCheck(nt->smooth_eps > 0 && PetscIsNormalReal(nt->smooth_eps), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_smoothing_eps %g must be positive", (double)nt->smooth_eps);
  PetscCheck(nt->rho_factor > 0 && PetscIsNormalReal(nt->rho_factor), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_rho %g must be positive", (double)nt->rho_factor);
  PetscCheck(nt->shift >= 0 && !PetscIsInfOrNanReal(nt->shift), s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_shift %g must be non-negative", (double)nt->shift);
  PetscCheck(nt->armijo > 0 && nt->armijo < 0.5, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-solver_newton_armijo %g must lie in (0, 0.5)",
             (double)nt->armijo);
  PetscCheck(nt->max_backtracks >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-solver_newton_max_backtracks %" PetscInt_FMT " must be non-negative", nt->max_backtracks);
  PetscCall(KSPSetFromOptions(nt->ksp));
  PetscCall(PresortApplies(s, nt, &nt->presort));
  if (nt->presort) { /* J arrives in W's AMD order (PresortContacts) */
    PC pc;
    PetscCall(KSPGetPC(nt->ksp, &pc));
    PetscCall(PCFactorSetMatOrderingType(pc, MATORDERINGNATURAL));
  }
  PetscCall(KSPSetTolerances(nt->kreuse, 1e-8, PETSC_DEFAULT, PETSC_DEFAULT, nt->reuse_its));
  PetscCall(KSPGMRESSetRestart(nt->kreuse, PetscMax(nt->reuse_its, 1)));
  PetscCall(KSPSetFromOptions(nt->kreuse));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverView_Newton(KergsSolver s, PetscViewer viewer)
{
  Newton *nt = (Newton *)s->data;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(
      viewer,
      "Semismooth Newton on the Alart-Curnier function (rho = %g / W_nn), Armijo line search (%g, at most %" PetscInt_FMT
      " halvings), shift %g\n",
      (double)nt->rho_factor, (double)nt->armijo, nt->max_backtracks, (double)nt->shift));
  if (nt->smoothing) {
    PetscCall(PetscViewerASCIIPrintf(
        viewer,
        "Smoothing Newton phase first: eps from %g times the largest |rho v^d_n|, Jacobian regularised by %g times the natural residual\n",
        (double)nt->smooth_eps, (double)nt->smooth_kappa));
    if (nt->smooth_raises > 0 && nt->stall_steps > 0)
      PetscCall(PetscViewerASCIIPrintf(
          viewer, "  its first %" PetscInt_FMT " stall(s) of a solve raise eps a hundredfold instead of ending it\n", nt->smooth_raises));
  }
  if (nt->presort) PetscCall(PetscViewerASCIIPrintf(viewer, "J stored in W's AMD order at every step, and factored in that order\n"));
  PetscCall(KSPView(nt->ksp, viewer));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverDestroy_Newton(KergsSolver s)
{
  Newton *nt = (Newton *)s->data;

  PetscFunctionBeginUser;
  PetscCall(DestroyStepObjects(nt));
  PetscCall(KSPDestroy(&nt->ksp));
  PetscCall(KSPDestroy(&nt->kreuse));
  PetscCall(PetscFree5(nt->A, nt->B, nt->rho, nt->rho_nat, nt->diagblock));
  PetscCall(PetscFree2(nt->Aused, nt->Bused));
  PetscCall(PetscFree2(nt->Afact, nt->Bfact));
  PetscCall(PetscFree(nt));
  s->data = NULL;
  PetscFunctionReturn(0);
}

/* One rank: a direct LU, PETSc's own with an AMD ordering (the fastest measured on the Jacobians of confine500 and
   biaxial 20k). Several ranks: chosen each step by ChooseLinearSolver. -solver_ksp_type, -solver_pc_type,
   -solver_pc_factor_mat_solver_type mumps (then with its null-pivot detection, EnableNullPivots) and the like choose
   otherwise. */
static PetscErrorCode CreateLinearSolver(KergsSolver s, Newton *nt)
{
  PC          pc;
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCall(KSPCreate(s->comm, &nt->ksp));
  PetscCall(KSPSetOptionsPrefix(nt->ksp, "solver_"));
  PetscCall(KSPSetType(nt->ksp, KSPPREONLY));
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(PCSetType(pc, PCLU));
  PetscCall(PCFactorSetMatSolverType(pc, size > 1 ? MATSOLVERMUMPS : MATSOLVERPETSC)); /* -solver_pc_type lu on several */
  PetscCall(PCFactorSetMatOrderingType(pc, MATORDERINGAMD)); /* 1.6-2.5 times faster than nd here; natural on one rank
                                                                 when J arrives presorted (PresortContacts) */
  PetscCall(KSPSetErrorIfNotConverged(nt->ksp, PETSC_FALSE));
  /* the reuse solver: GMRES on the unpreconditioned residual, preconditioned on the right by ksp's last factorization */
  PetscCall(KSPCreate(s->comm, &nt->kreuse));
  PetscCall(KSPSetOptionsPrefix(nt->kreuse, "solver_reuse_"));
  PetscCall(KSPSetType(nt->kreuse, KSPGMRES));
  PetscCall(KSPSetPCSide(nt->kreuse, PC_RIGHT));
  PetscCall(KSPSetNormType(nt->kreuse, KSP_NORM_UNPRECONDITIONED));
  PetscCall(KSPGetPC(nt->kreuse, &pc));
  PetscCall(PCSetType(pc, PCSHELL));
  PetscCall(PCShellSetContext(pc, nt));
  PetscCall(PCShellSetApply(pc, ApplyStaleFactor));
  PetscCall(PCShellSetName(pc, "the last factorization of J"));
  PetscCall(KSPSetErrorIfNotConverged(nt->kreuse, PETSC_FALSE));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverCreate_Newton(KergsSolver s)
{
  Newton *nt;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&nt));
  nt->rho_factor     = 1.0;
  nt->shift          = 1e-8;
  nt->armijo         = 1e-4;
  nt->max_backtracks = 33;
  nt->switch_tol     = 1e-2;
  nt->max_sweeps     = 0;
  nt->sweep_check    = 10;
  nt->prox           = NEWTON_PROX_IDENTITY;
  nt->alpha          = 10.0;
  nt->alpha_min      = 1e-3;
  nt->sigma_min      = 1e-8;
  nt->sigma_max      = 1.0;
  nt->inner_max      = 20;
  nt->stall_steps    = 5;
  nt->redundant_max  = 15000;
  nt->inner_rtol     = 0.1;
  nt->reuse_its      = 10;
  nt->smooth_kappa   = 0.3;
  nt->smoothing      = PETSC_TRUE;
  nt->smooth_eps     = 4.0;
  nt->smooth_raises  = 1;
  PetscCall(CreateLinearSolver(s, nt));
  s->data               = nt;
  s->max_it             = 100;
  s->tol                = 1e-10;
  s->criterion          = KERGS_CRITERION_NATURAL;
  s->fixed_criterion    = PETSC_TRUE;
  s->iteration_name     = "Newton steps";
  s->ops.setfromoptions = SolverSetFromOptions_Newton;
  s->ops.setup          = SolverSetUp_Newton;
  s->ops.solve          = SolverSolve_Newton;
  s->ops.stats          = SolverStats_Newton;
  s->ops.view           = SolverView_Newton;
  s->ops.destroy        = SolverDestroy_Newton;
  PetscFunctionReturn(0);
}
