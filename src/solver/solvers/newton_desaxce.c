/* newton's De Saxce start (-solver_newton_desaxce_max_it): a few outer iterations of De Saxce's fixed point before
   Newton, to put the warm start on the solution's pieces (docs/solver.md, "A De Saxce start").

   With the shift s = mu |u_t| fixed, Coulomb's problem (r in the cone K, u + s e_n in its dual, complementary) is a
   convex QP whose velocities u are unique even where ker W leaves r undetermined (Acary, Cadoux, Lemarechal and
   Malick, ZAMM 2011). In 2D the cone |r_t| <= mu r_n is spanned by its edges (1, +-mu): r = E z with z = (a, b) >= 0
   per contact, E = [[1, 1], [mu, -mu]], and the QP is bound-constrained,
     min 1/2 z^T E^T W E z + z^T E^T (v^d + s e_n)   subject to   z >= 0,
   solved by TAO's interior point (BQPIP) with a direct solve of its Newton systems. At a fixed point s = mu |u_t|, (r, u)
   solves the problem. On dense frictional packings at rest of a few thousand grains Newton's merit stalls on wrong
   pieces; after one loosely solved QP Newton finishes in a few steps. */
#include "newton.h"

#define PROX 1e-8 /* the QPs' proximal coefficient, relative to the mean W_nn */

typedef struct {
  KergsQuadratic qp;      /* H: E^T W E over the active contacts (+ a proximal term); c: the linear term */
  Mat            E;       /* edge coordinates to the active contacts' impulses */
  IS             is;      /* the active components, global indices of r */
  Vec            z, w;    /* the QP's unknowns, work on the active components */
  Vec            lb, ub;  /* z >= 0 */
  PetscReal     *shift;   /* per local active contact */
  PetscInt       nactive; /* local active contacts */
  Tao            tao;     /* prefix solver_newton_desaxce_ */
  PetscReal      wmean;   /* mean W_nn: velocities to impulses */
  PetscReal      kkt_tol; /* the QP's KKT residual that ends it, in impulse units */
  PetscReal      kkt;     /* its last value */
  PetscReal      bound;   /* z's upper bound, meant never to bind */
} DeSaxce;

/* TAO's convergence test for BQPIP: the QP's own natural residual |min(z, g / mean W_nn)|, g = H z + c its gradient (the
   KKT conditions of z >= 0: 0 <= z _|_ g >= 0), in impulse units, at most kkt_tol. BQPIP's own measure mixes the
   duality gap with the gradient's 1-norm and stagnates above any tolerance tied to the contact problem (measured). */
static PetscErrorCode ConvergenceTest(Tao tao, void *ctx)
{
  DeSaxce           *ds = (DeSaxce *)ctx;
  const PetscScalar *zl, *gl;
  PetscInt           m, its, max_it;
  PetscReal          sum = 0.0;
  Vec                z;

  PetscFunctionBeginUser;
  PetscCall(TaoGetSolution(tao, &z));
  PetscCall(MatMult(ds->qp.H, z, ds->w));
  PetscCall(VecAXPY(ds->w, 1.0, ds->qp.c));
  PetscCall(VecGetLocalSize(z, &m));
  PetscCall(VecGetArrayRead(z, &zl));
  PetscCall(VecGetArrayRead(ds->w, &gl));
  for (PetscInt i = 0; i < m; i++) sum += PetscSqr(PetscMin(PetscRealPart(zl[i]), PetscRealPart(gl[i]) / ds->wmean));
  PetscCall(VecRestoreArrayRead(ds->w, &gl));
  PetscCall(VecRestoreArrayRead(z, &zl));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sum, 1, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)tao)));
  ds->kkt = PetscSqrtReal(sum);
  PetscCall(TaoGetIterationNumber(tao, &its));
  PetscCall(TaoGetMaximumIterations(tao, &max_it));
  if (PetscIsInfOrNanReal(ds->kkt))
    PetscCall(TaoSetConvergedReason(tao, TAO_DIVERGED_NAN));
  else if (ds->kkt <= ds->kkt_tol)
    PetscCall(TaoSetConvergedReason(tao, TAO_CONVERGED_USER));
  else if (its >= max_it)
    PetscCall(TaoSetConvergedReason(tao, TAO_DIVERGED_MAXITS));
  else
    PetscCall(TaoSetConvergedReason(tao, TAO_CONTINUE_ITERATING));
  PetscFunctionReturn(0);
}

/* The Tao: BQPIP, its Newton systems solved directly (Cholesky: CHOLMOD on one rank, MUMPS on several), then the
   options under solver_newton_desaxce_, so that -solver_newton_desaxce_tao_* and _ksp_/_pc_ options apply. */
PetscErrorCode NewtonDeSaxceCreateTao(KergsSolver s, Tao *tao)
{
  char        prefix[256];
  KSP         ksp;
  PC          pc;
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCall(KergsSolverInnerPrefix(s, "solver_newton_desaxce_", prefix, sizeof(prefix)));
  PetscCall(MPI_Comm_size(s->comm, &size));
  PetscCall(TaoCreate(s->comm, tao));
  PetscCall(TaoSetOptionsPrefix(*tao, prefix));
  PetscCall(TaoSetType(*tao, TAOBQPIP));
  PetscCall(TaoSetMaximumIterations(*tao, 200));
  PetscCall(TaoGetKSP(*tao, &ksp));
  PetscCall(KSPSetType(ksp, KSPPREONLY));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCCHOLESKY));
  PetscCall(PCFactorSetMatSolverType(pc, size == 1 ? MATSOLVERCHOLMOD : MATSOLVERMUMPS));
  PetscCall(TaoSetFromOptions(*tao));
  PetscFunctionReturn(0);
}

/* The QP of this step: the active components, E, H = E^T W E, the vectors and the Tao. */
static PetscErrorCode SetUp(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, PetscReal wmean, PetscReal scale, DeSaxce *ds)
{
  PetscInt rstart, m, k = 0;
  Mat      Wa;

  PetscFunctionBeginUser;
  PetscCall(KergsSolverActiveSubmatrix(s, nt->Wfull, n, nc, &ds->is, &Wa));
  PetscCall(ISGetLocalSize(ds->is, &m));
  ds->nactive = m / nc;
  ds->wmean   = wmean;
  ds->kkt_tol = nt->desaxce_qp_tol * scale;
  ds->bound   = 100.0 * scale;
  PetscCall(MatCreateAIJ(s->comm, m, m, PETSC_DETERMINE, PETSC_DETERMINE, 2, NULL, 0, NULL, &ds->E));
  PetscCall(MatGetOwnershipRange(ds->E, &rstart, NULL));
  for (PetscInt a = 0; a < n; a++) {
    if (!s->active[a]) continue;
    const PetscInt    rows[2] = {rstart + 2 * k, rstart + 2 * k + 1};
    const PetscScalar vals[4] = {1.0, 1.0, s->mu[a], -s->mu[a]};
    PetscCall(MatSetValues(ds->E, 2, rows, 2, rows, vals, INSERT_VALUES));
    k++;
  }
  PetscCall(MatAssemblyBegin(ds->E, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ds->E, MAT_FINAL_ASSEMBLY));
  PetscCall(MatPtAP(Wa, ds->E, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &ds->qp.H));
  PetscCall(MatDestroy(&Wa));
  /* E^T W E is singular with W (and along a - b on a contact without friction, whose edges coincide), and its rounding
     left CHOLMOD a negative pivot where BQPIP's barrier term is small (measured on biaxial_5k's first step): a proximal
     term sigma |z - z_k|^2 / 2 with sigma = 1e-8 mean W_nn, which vanishes at the fixed point */
  PetscCall(MatShift(ds->qp.H, PROX * wmean));
  PetscCall(MatSetOption(ds->qp.H, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatCreateVecs(ds->qp.H, &ds->z, &ds->qp.c));
  PetscCall(VecDuplicate(ds->z, &ds->w));
  PetscCall(VecDuplicate(ds->z, &ds->lb));
  PetscCall(VecDuplicate(ds->z, &ds->ub));
  PetscCall(VecSet(ds->lb, 0.0));
  /* no impulse exceeds 100 times the problem's scale (max(|r|, |p|) over all contacts): a finite bound that is never
     reached keeps BQPIP's first point in proportion (with +inf its first residual was 1e12 and 40 iterations went to
     bringing it down) */
  PetscCall(VecSet(ds->ub, ds->bound));
  PetscCall(PetscMalloc1(ds->nactive + 1, &ds->shift));
  PetscCall(NewtonDeSaxceCreateTao(s, &ds->tao));
  PetscCall(KergsQuadraticSetTao(&ds->qp, ds->tao));
  PetscCall(TaoSetVariableBounds(ds->tao, ds->lb, ds->ub));
  PetscCall(TaoSetConvergenceTest(ds->tao, ConvergenceTest, ds));
  PetscFunctionReturn(0);
}

static PetscErrorCode Destroy(DeSaxce *ds)
{
  PetscFunctionBeginUser;
  PetscCall(TaoDestroy(&ds->tao));
  PetscCall(MatDestroy(&ds->qp.H));
  PetscCall(MatDestroy(&ds->E));
  PetscCall(ISDestroy(&ds->is));
  PetscCall(VecDestroy(&ds->z));
  PetscCall(VecDestroy(&ds->qp.c));
  PetscCall(VecDestroy(&ds->w));
  PetscCall(VecDestroy(&ds->lb));
  PetscCall(VecDestroy(&ds->ub));
  PetscCall(PetscFree(ds->shift));
  PetscFunctionReturn(0);
}

/* z from the impulses r: a = (r_n + r_t / mu) / 2, b = (r_n - r_t / mu) / 2, projected on z >= 0 (a = b = r_n / 2
   without friction); and s = mu |u_t| from the velocities u = W r + v^d. */
static PetscErrorCode FromImpulses(KergsSolver s, DeSaxce *ds, PetscInt n, Vec r, Vec u)
{
  const PetscScalar *rl, *ul;
  PetscScalar       *zl;
  PetscInt           k = 0;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(r, &rl));
  PetscCall(VecGetArrayRead(u, &ul));
  PetscCall(VecGetArray(ds->z, &zl));
  for (PetscInt a = 0; a < n; a++) {
    if (!s->active[a]) continue;
    const PetscReal rn = PetscRealPart(rl[2 * a]), slope = s->mu[a] > 0 ? PetscRealPart(rl[2 * a + 1]) / s->mu[a] : 0.0;
    zl[2 * k]     = PetscMax(0.5 * (rn + slope), 0.0);
    zl[2 * k + 1] = PetscMax(0.5 * (rn - slope), 0.0);
    ds->shift[k]  = s->mu[a] * PetscAbsScalar(ul[2 * a + 1]);
    k++;
  }
  PetscCall(VecRestoreArray(ds->z, &zl));
  PetscCall(VecRestoreArrayRead(u, &ul));
  PetscCall(VecRestoreArrayRead(r, &rl));
  PetscFunctionReturn(0);
}

/* One QP with the current shift, from the current z: c = E^T (v^d + s e_n), the solve, and r = E z (inactive
   components stay 0). */
static PetscErrorCode SolveQP(DeSaxce *ds, Vec r, Vec vd, PetscInt *its, PetscBool *solved)
{
  TaoConvergedReason reason;
  PetscScalar       *wl;
  Vec                sub;

  PetscFunctionBeginUser;
  PetscCall(VecGetSubVector(vd, ds->is, &sub));
  PetscCall(VecCopy(sub, ds->w));
  PetscCall(VecRestoreSubVector(vd, ds->is, &sub));
  PetscCall(VecGetArray(ds->w, &wl));
  for (PetscInt k = 0; k < ds->nactive; k++) wl[2 * k] += ds->shift[k];
  PetscCall(VecRestoreArray(ds->w, &wl));
  PetscCall(MatMultTranspose(ds->E, ds->w, ds->qp.c));
  PetscCall(VecAXPY(ds->qp.c, -PROX * ds->wmean, ds->z)); /* the proximal centre z_k */
  PetscCall(TaoSetSolution(ds->tao, ds->z));
  PetscCall(TaoSolve(ds->tao));
  PetscCall(TaoGetIterationNumber(ds->tao, its));
  PetscCall(TaoGetConvergedReason(ds->tao, &reason));
  *solved = (PetscBool)(reason > 0);
  /* BQPIP keeps its slacks positive, not z: a loose answer may have z slightly negative, r = E z outside its cone */
  PetscCall(VecPointwiseMax(ds->z, ds->z, ds->lb));
  { /* the bound is meant never to bind (SetUp): say so when it comes near (measured: 17 times the scale at most, on the
       biaxial test's first step, against 100) */
    PetscReal zmax;
    PetscCall(VecMax(ds->z, NULL, &zmax));
    if (zmax > 0.5 * ds->bound)
      PetscCall(PetscInfo(NULL, "De Saxce QP: an edge coordinate %g is near its bound %g\n", (double)zmax, (double)ds->bound));
  }
  PetscCall(MatMult(ds->E, ds->z, ds->w));
  PetscCall(VecSet(r, 0.0));
  PetscCall(VecISCopy(r, ds->is, SCATTER_FORWARD, ds->w));
  PetscFunctionReturn(0);
}

/* From r (u = W r + v^d and *res its natural residual on entry), De Saxce QPs until the natural residual is at most
   -solver_newton_desaxce_tol or -solver_newton_desaxce_max_it QPs; r and u end at the best answer by natural residual
   (the warm start if no QP improved on it). Each QP is solved until its own natural residual (ConvergenceTest) is
   -solver_newton_desaxce_qp_tol times the problem's impulse scale: loosely (1e-3 by default). A loose answer lies
   inside the cones where a tight one reaches for their faces, and Newton finishes from it in fewer steps (measured:
   on the 2,700-disk rest step one QP of 20 interior-point iterations, then 5 Newton steps; three tight QPs of 30 each,
   then 8). Friction only: nc = 2. */
PetscErrorCode NewtonDeSaxceStart(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, PetscReal wmean, PetscReal scale, Vec r, Vec u,
                                  Vec vd, PetscReal *res)
{
  DeSaxce         ds     = {0};
  PetscReal       best   = *res;
  const PetscReal target = PetscMax(nt->desaxce_tol, s->tol);
  PetscLogDouble  t0, t1;

  PetscFunctionBeginUser;
  if (nc != 2 || *res <= target || nt->desaxce_max_it <= 0) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(KERGS_DeSaxce, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  PetscCall(SetUp(s, nt, n, nc, wmean, scale, &ds));
  PetscCall(VecCopy(r, nt->rbest));
  PetscCall(FromImpulses(s, &ds, n, r, u));
  for (PetscInt k = 0; k < nt->desaxce_max_it && best > target; k++) {
    PetscInt  its    = 0;
    PetscBool solved = PETSC_FALSE;
    PetscReal now;
    PetscCall(SolveQP(&ds, r, vd, &its, &solved));
    nt->desaxce_qps++;
    nt->desaxce_ip_its += its;
    PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
    PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, &now));
    PetscCall(PetscInfo(NULL,
                        "De Saxce QP %" PetscInt_FMT ": %" PetscInt_FMT " interior-point iterations%s (KKT %g), natural residual %g\n",
                        k + 1, its, solved ? "" : " (not converged)", (double)ds.kkt, (double)now));
    if (now < best) {
      best = now;
      PetscCall(VecCopy(r, nt->rbest));
    }
    if (!(now < PETSC_MAX_REAL) || (!solved && now >= best)) break; /* a QP left unsolved may still have helped */
    if (its == 0) break;                      /* its start met the QP's tolerance: the fixed point no longer moves at this tolerance */
    PetscCall(FromImpulses(s, &ds, n, r, u)); /* the next shift, and z from r (the same z where mu > 0) */
  }
  PetscCall(VecCopy(nt->rbest, r));
  PetscCall(MatMultAdd(nt->Wfull, r, vd, u));
  PetscCall(NewtonNaturalResidual(s, nt, n, nc, r, u, res)); /* best, and nt->enorm of r itself */
  PetscCall(Destroy(&ds));
  PetscCall(PetscTime(&t1));
  nt->desaxce_seconds += t1 - t0;
  PetscCall(PetscLogEventEnd(KERGS_DeSaxce, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
