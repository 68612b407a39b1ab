/* kergs predictor: the prediction r~ of NLKerGS-P (Algorithm 3), by a type chosen by name (-predictor_type),
   the way PETSc chooses a KSP. This file holds what the types share: the registry, the options, the active
   set, the scaling of eta and epsilon, and the DOF-space solve of Algorithms 4 and 5. */
#include <kergs/private/predictorimpl.h>

static PetscFunctionList PredictorList = NULL;

PetscErrorCode KergsPredictorRegister(const char name[], PetscErrorCode (*create)(KergsPredictor))
{
  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListAdd(&PredictorList, name, create));
  PetscFunctionReturn(0);
}

/* Forget the registry at PetscFinalize (PETSc may be initialized again). */
static PetscErrorCode PredictorFinalizePackage(void)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListDestroy(&PredictorList));
  PetscFunctionReturn(0);
}

static PetscErrorCode PredictorRegisterAll(void)
{
  PetscFunctionBeginUser;
  if (PredictorList) PetscFunctionReturn(0);
  PetscCall(PetscRegisterFinalize(PredictorFinalizePackage));
  PetscCall(KergsPredictorRegister(KERGS_PREDICTOR_NONE, KergsPredictorCreate_None));
  PetscCall(KergsPredictorRegister(KERGS_PREDICTOR_LINEAR, KergsPredictorCreate_Linear));
  PetscCall(KergsPredictorRegister(KERGS_PREDICTOR_UNILATERAL, KergsPredictorCreate_Unilateral));
  PetscCall(KergsPredictorRegister(KERGS_PREDICTOR_ELASTIC, KergsPredictorCreate_Elastic));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorCreate(MPI_Comm comm, KergsPredictor *predictor)
{
  KergsPredictor p;

  PetscFunctionBeginUser;
  PetscCall(PredictorRegisterAll());
  PetscCall(KergsInitializePackage());
  PetscCall(PetscNew(&p));
  p->comm      = comm;
  p->eta       = 1e-6; /* relative: see predictor.h */
  p->epsilon   = 1.0;  /* relative: see predictor.h */
  p->relative  = PETSC_TRUE;
  p->wmean     = 1.0;
  p->converged = PETSC_TRUE;
  *predictor   = p;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorSetType(KergsPredictor p, KergsPredictorType type)
{
  PetscErrorCode (*create)(KergsPredictor);

  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListFind(PredictorList, type, &create));
  PetscCheck(create, p->comm, PETSC_ERR_ARG_UNKNOWN_TYPE,
             "Unknown -predictor_type %s (registered: none, linear, unilateral, elastic; see -help)", type);
  if (p->ops.destroy) PetscCall((*p->ops.destroy)(p));
  PetscCall(PetscMemzero(&p->ops, sizeof(p->ops)));
  p->data = NULL;
  PetscCall(KSPDestroy(&p->ksp)); /* a type that needs one creates it */
  PetscCall(VecDestroy(&p->Vtilde));
  PetscCall(PetscStrncpy(p->type, type, sizeof(p->type)));
  PetscCall((*create)(p));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorSetFromOptions(KergsPredictor p)
{
  char      type[64] = KERGS_PREDICTOR_NONE;
  PetscBool set;

  PetscFunctionBeginUser;
  if (p->type[0]) PetscCall(PetscStrncpy(type, p->type, sizeof(type)));
  PetscOptionsBegin(p->comm, p->prefix[0] ? p->prefix : NULL, "Predictor options (NLKerGS-P, Algorithm 3)", NULL);
  PetscCall(
      PetscOptionsFList("-predictor_type",
                        "Prediction r~ of the impulses: none, linear (Algorithm 4), unilateral (exact frictionless), elastic (Algorithm 5)",
                        "KergsPredictorSetType", PredictorList, type, type, sizeof(type), &set));
  if (!p->ops.predict || set) PetscCall(KergsPredictorSetType(p, type));
  /* the parameters of linear and elastic are fields of every predictor, so that -help always lists them */
  PetscCall(PetscOptionsReal(
      "-predictor_eta",
      "linear: eta > 0 of r_n = -(dt/eta) v_n, relative to dt * mean W_nn (dimensionless), or in s/kg with -predictor_relative 0", "",
      p->eta, &p->eta, NULL));
  PetscCall(PetscOptionsReal("-predictor_epsilon",
                             "elastic: epsilon > 0 of r_n = -(dt/epsilon) g+ (a compliance), relative to dt^2 * mean W_nn (dimensionless), "
                             "or in s^2/kg with -predictor_relative 0",
                             "", p->epsilon, &p->epsilon, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-predictor_relative",
                             "linear, elastic: eta and epsilon relative to the mean W_nn of the active contacts (else absolute)", "",
                             p->relative, &p->relative, NULL));
  if (p->ops.setfromoptions) PetscCall((*p->ops.setfromoptions)(PetscOptionsObject, p));
  PetscOptionsEnd();
  PetscCheck(p->eta > 0 && PetscIsNormalReal(p->eta), p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-predictor_eta %g must be a positive finite number", (double)p->eta);
  PetscCheck(p->epsilon > 0 && PetscIsNormalReal(p->epsilon), p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-predictor_epsilon %g must be a positive finite number", (double)p->epsilon);
  if (p->ksp) PetscCall(KSPSetFromOptions(p->ksp));
  PetscFunctionReturn(0);
}

/* Direct Cholesky by default: K = M + c A^T A is SPD but, for small eta or epsilon, has a condition number
   of about 1/eta (relative), which an unpreconditioned iterative solver would not survive; a Cholesky
   factorization is backward stable whatever the conditioning. CHOLMOD on one rank (PETSc's own Cholesky if
   SuiteSparse is missing), MUMPS on several. Users override with -predictor_ksp_type, -predictor_pc_type ... */
PetscErrorCode KergsPredictorCreateKSP(KergsPredictor p)
{
  PC          pc;
  PetscMPIInt size;
  PetscBool   has;

  PetscFunctionBeginUser;
  if (p->ksp) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_size(p->comm, &size));
  PetscCall(KSPCreate(p->comm, &p->ksp));
  PetscCall(KSPSetOptionsPrefix(p->ksp, p->prefix));
  PetscCall(KSPAppendOptionsPrefix(p->ksp, "predictor_"));
  PetscCall(KSPSetType(p->ksp, KSPPREONLY));
  PetscCall(KSPGetPC(p->ksp, &pc));
  PetscCall(PCSetType(pc, PCCHOLESKY));
  if (size == 1) {
    PetscCall(PetscHasExternalPackage("suitesparse", &has));
    PetscCall(PCFactorSetMatSolverType(pc, has ? MATSOLVERCHOLMOD : MATSOLVERPETSC));
  } else
    PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  PetscFunctionReturn(0);
}

/* Local offsets (into the layout of in->r) of the normal components of the active local contacts. */
static PetscErrorCode ActiveNormalOffsets(const KergsPredictorInput *in, const PetscBool *active, PetscInt *nact, PetscInt **offsets)
{
  PetscFunctionBeginUser;
  *nact = 0;
  for (PetscInt k = 0; k < in->ncontacts; k++)
    if (active[k]) (*nact)++;
  PetscCall(PetscMalloc1(*nact, offsets));
  *nact = 0;
  for (PetscInt k = 0; k < in->ncontacts; k++)
    if (active[k]) (*offsets)[(*nact)++] = k * in->L.ncomp;
  PetscFunctionReturn(0);
}

/* K = M + c A^T A over the free DOFs. A^T A = H_f D H_f^T since D is a 0/1 selector (D^1/2 = D). DOFs that
   no active contact touches have no diagonal entry in A^T A: M is added as a matrix of its own
   (DIFFERENT_NONZERO_PATTERN), so that every row gets its diagonal. */
static PetscErrorCode AssembleK(const KergsPredictorInput *in, Mat A, PetscReal c, Vec Mdiag, Mat *K)
{
  Mat      Mmat;
  PetscInt lo, hi;

  PetscFunctionBeginUser;
  PetscCall(MatTransposeMatMult(A, A, MAT_INITIAL_MATRIX, PETSC_DEFAULT, K));
  PetscCall(MatScale(*K, c));
  PetscCall(MatCreateAIJ(PetscObjectComm((PetscObject)A), in->L.nfree_local, in->L.nfree_local, in->L.nfree, in->L.nfree, 1, NULL, 0, NULL,
                         &Mmat));
  PetscCall(VecGetOwnershipRange(Mdiag, &lo, &hi));
  {
    const PetscScalar *m;
    PetscCall(VecGetArrayRead(Mdiag, &m));
    for (PetscInt i = lo; i < hi; i++) PetscCall(MatSetValue(Mmat, i, i, m[i - lo], INSERT_VALUES));
    PetscCall(VecRestoreArrayRead(Mdiag, &m));
  }
  PetscCall(MatAssemblyBegin(Mmat, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(Mmat, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAXPY(*K, 1.0, Mmat, DIFFERENT_NONZERO_PATTERN));
  PetscCall(MatDestroy(&Mmat));
  PetscCall(MatSetOption(*K, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatSetOption(*K, MAT_SPD, PETSC_TRUE));
  PetscFunctionReturn(0);
}

/* Solve K V~ = b with p->ksp; the reason is reduced over ranks (a failed factorization may be flagged on one
   rank only) and the solution must be finite: MUMPS failures are otherwise silent (docs/design.md: toolchain notes). */
static PetscErrorCode SolveK(KergsPredictor p, Mat K, Vec b, Vec x)
{
  KSPConvergedReason reason;
  PetscInt           r;
  KSPType            ktype;
  PetscBool          preonly;
  PetscReal          nx;

  PetscFunctionBeginUser;
  {
    /* after a repartition the DOFs of a rank change: PETSc refuses new local sizes for a KSP's operator */
    PetscBool set;
    Mat       Kold;
    PetscInt  m, mold;
    PetscCall(KSPGetOperatorsSet(p->ksp, &set, NULL));
    if (set) {
      PetscCall(KSPGetOperators(p->ksp, &Kold, NULL));
      PetscCall(MatGetLocalSize(Kold, &mold, NULL));
      PetscCall(MatGetLocalSize(K, &m, NULL));
      if (m != mold) PetscCall(KSPReset(p->ksp));
    }
  }
  PetscCall(KSPSetOperators(p->ksp, K, K));
  PetscCall(KSPSolve(p->ksp, b, x));
  PetscCall(KSPGetConvergedReason(p->ksp, &reason));
  /* failures are negative, successes positive: the minimum over ranks is a failure if any rank failed */
  PetscCall(MPIU_Allreduce((PetscInt[]){(PetscInt)reason}, &r, 1, MPIU_INT, MPI_MIN, p->comm));
  PetscCheck(r != (PetscInt)KSP_DIVERGED_PC_FAILED, p->comm, PETSC_ERR_CONV_FAILED,
             "predictor (%s): the factorization of M + c H_f D H_f^T failed (%s); try -predictor_pc_factor_mat_solver_type mumps or a "
             "larger -predictor_eta / -predictor_epsilon",
             p->type, KSPConvergedReasons[r]);
  PetscCheck(r >= 0 || r == (PetscInt)KSP_DIVERGED_ITS, p->comm, PETSC_ERR_CONV_FAILED,
             "predictor (%s): the solve of M + c H_f D H_f^T failed (%s); see -predictor_ksp_type, -predictor_pc_type", p->type,
             KSPConvergedReasons[r]);
  p->converged = (PetscBool)(r > 0);
  if (!p->converged)
    PetscCall(PetscInfo(NULL, "predictor (%s): the KSP stopped at its iteration cap; the prediction is approximate\n", p->type));
  PetscCall(VecNorm(x, NORM_INFINITY, &nx));
  PetscCheck(!PetscIsInfOrNanReal(nx), p->comm, PETSC_ERR_FP,
             "predictor (%s): V~ is not finite (NaN or Inf) after the solve of M + c H_f D H_f^T", p->type);
  PetscCall(KSPGetType(p->ksp, &ktype));
  PetscCall(PetscStrcmp(ktype, KSPPREONLY, &preonly));
  if (preonly)
    p->ksp_its = 0;
  else
    PetscCall(KSPGetIterationNumber(p->ksp, &p->ksp_its));
  PetscFunctionReturn(0);
}

/* Algorithms 4 and 5 in one form (predictor.h): with A = D H_f^T restricted to the active normal rows,
     (M + c A^T A) V~ = R^d + M V_f^- - A^T q,   r~_n = -(q + c A V~).
   Linear: c = dt/eta, q = c H_g^T V_g^+; elastic: c = theta dt^2/eps, q = (dt/eps)(g^- + ...) (elastic.c). */
PetscErrorCode KergsPredictorSolveRegularised(KergsPredictor p, const KergsPredictorInput *in, const PetscBool *active, PetscReal c, Vec q,
                                              Vec rtilde)
{
  PetscInt           nact, *off, cstart, cend, *rows;
  IS                 isrow, iscol;
  Mat                A, K;
  Vec                Mdiag, b, qa, ra;
  PetscScalar       *a, *rt;
  const PetscScalar *qf;

  PetscFunctionBeginUser;
  PetscCheck(p->ksp, p->comm, PETSC_ERR_ORDER, "predictor (%s): no KSP; call KergsPredictorCreateKSP in the type's create", p->type);
  /* A = the active normal rows of H_f^T, all (local) columns */
  PetscCall(ActiveNormalOffsets(in, active, &nact, &off));
  PetscCall(PetscMalloc1(nact, &rows));
  for (PetscInt i = 0; i < nact; i++) rows[i] = in->start * in->L.ncomp + off[i];
  PetscCall(ISCreateGeneral(p->comm, nact, rows, PETSC_OWN_POINTER, &isrow));
  PetscCall(VecGetOwnershipRange(in->Vf, &cstart, &cend));
  PetscCall(ISCreateStride(p->comm, cend - cstart, cstart, 1, &iscol));
  PetscCall(MatCreateSubMatrix(in->HfT, isrow, iscol, MAT_INITIAL_MATRIX, &A));
  PetscCall(ISDestroy(&isrow));
  PetscCall(ISDestroy(&iscol));

  /* K and b = R^d + M V_f^- - A^T q */
  PetscCall(VecDuplicate(in->Minv, &Mdiag));
  PetscCall(VecCopy(in->Minv, Mdiag));
  PetscCall(VecReciprocal(Mdiag));
  PetscCall(AssembleK(in, A, c, Mdiag, &K));
  PetscCall(MatCreateVecs(A, NULL, &qa));
  PetscCall(VecDuplicate(qa, &ra));
  PetscCall(VecGetArrayRead(q, &qf));
  PetscCall(VecGetArray(qa, &a));
  for (PetscInt i = 0; i < nact; i++) a[i] = qf[off[i]];
  PetscCall(VecRestoreArray(qa, &a));
  PetscCall(VecRestoreArrayRead(q, &qf));
  PetscCall(VecDuplicate(in->Vf, &b));
  PetscCall(MatMultTranspose(A, qa, b));
  PetscCall(VecScale(b, -1.0));
  PetscCall(VecPointwiseMult(Mdiag, Mdiag, in->Vf)); /* Mdiag <- M V_f^- */
  PetscCall(VecAXPBYPCZ(b, 1.0, 1.0, 1.0, in->Rd, Mdiag));

  PetscCall(VecDestroy(&p->Vtilde));
  PetscCall(VecDuplicate(in->Vf, &p->Vtilde));
  PetscCall(SolveK(p, K, b, p->Vtilde));

  /* r~_n = -(q + c A V~) on the active normal components */
  PetscCall(MatMult(A, p->Vtilde, ra));
  PetscCall(VecAYPX(ra, c, qa));
  PetscCall(VecGetArray(rtilde, &rt));
  PetscCall(VecGetArray(ra, &a));
  for (PetscInt i = 0; i < nact; i++) rt[off[i]] = -a[i];
  PetscCall(VecRestoreArray(ra, &a));
  PetscCall(VecRestoreArray(rtilde, &rt));

  PetscCall(VecDestroy(&qa));
  PetscCall(VecDestroy(&ra));
  PetscCall(VecDestroy(&b));
  PetscCall(VecDestroy(&Mdiag));
  PetscCall(MatDestroy(&K));
  PetscCall(MatDestroy(&A));
  PetscCall(PetscFree(off));
  PetscFunctionReturn(0);
}

/* Active set (the caller's, or g^- <= 0), its global count, and the mean W_nn over it, which scales
   relative eta and epsilon (predictor.h). */
static PetscErrorCode ActiveAndScale(KergsPredictor p, const KergsPredictorInput *in, const PetscBool *active, PetscBool *act)
{
  Vec                diag;
  const PetscScalar *d;
  PetscReal          sums[2] = {0, 0};

  PetscFunctionBeginUser;
  PetscCall(MatCreateVecs(in->W, &diag, NULL));
  PetscCall(MatGetDiagonal(in->W, diag));
  PetscCall(VecGetArrayRead(diag, &d));
  for (PetscInt k = 0; k < in->ncontacts; k++) {
    act[k] = active ? active[k] : (PetscBool)(in->c[k].gap <= 0.0);
    if (!act[k]) continue;
    sums[0] += PetscRealPart(d[k * in->L.ncomp]);
    sums[1] += 1.0;
  }
  PetscCall(VecRestoreArrayRead(diag, &d));
  PetscCall(VecDestroy(&diag));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 2, MPIU_REAL, MPIU_SUM, p->comm));
  p->nactive     = (PetscInt)sums[1];
  p->wmean       = sums[1] > 0 && sums[0] > 0 ? sums[0] / sums[1] : 1.0;
  p->eta_abs     = p->relative ? p->eta * in->dt * p->wmean : p->eta;
  p->epsilon_abs = p->relative ? p->epsilon * in->dt * in->dt * p->wmean : p->epsilon;
  PetscFunctionReturn(0);
}

static PetscErrorCode GetPredictorInput(KergsScene scene, KergsContacts contacts, KergsOperators ops, KergsPredictorInput *in)
{
  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetTimeStep(scene, &in->dt, &in->theta));
  PetscCall(KergsContactsGetLocal(contacts, &in->ncontacts, &in->c));
  PetscCall(KergsContactsGetGlobalRange(contacts, &in->start, NULL));
  PetscCall(KergsOperatorsGetLayout(ops, &in->L));
  PetscCall(KergsOperatorsGetH(ops, &in->HfT, &in->HgT));
  PetscCall(KergsOperatorsGetW(ops, &in->W, NULL));
  PetscCall(KergsOperatorsGetContactVectors(ops, &in->r, NULL, &in->vd));
  PetscCall(KergsOperatorsGetDofVectors(ops, &in->Vf, &in->Minv, &in->Rd, &in->Vg));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorPredict(KergsPredictor p, KergsScene scene, KergsContacts contacts, KergsOperators ops,
                                     const PetscBool *active, Vec rtilde)
{
  PetscLogDouble      t0, t1;
  PetscInt            m;
  PetscBool          *act;
  KergsPredictorInput input, *in = &input;

  PetscFunctionBeginUser;
  PetscCall(GetPredictorInput(scene, contacts, ops, in));
  PetscCheck(p->ops.predict, p->comm, PETSC_ERR_ORDER, "Call KergsPredictorSetFromOptions() or KergsPredictorSetType() first");
  PetscCall(VecGetLocalSize(rtilde, &m));
  PetscCheck(m == in->ncontacts * in->L.ncomp, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ,
             "KergsPredictorPredict: r~ has %" PetscInt_FMT " local entries, expected %" PetscInt_FMT " contacts x %" PetscInt_FMT
             " components",
             m, in->ncontacts, in->L.ncomp);
  PetscCall(PetscLogEventBegin(KERGS_Predict, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  PetscCall(VecDestroy(&p->Vtilde));
  p->ksp_its   = 0;
  p->sweeps    = 0;
  p->converged = PETSC_TRUE;
  PetscCall(VecZeroEntries(rtilde)); /* tangential and inactive components stay zero */
  PetscCall(PetscMalloc1(in->ncontacts, &act));
  PetscCall(ActiveAndScale(p, in, active, act));
  if (p->nactive > 0) PetscCall((*p->ops.predict)(p, in, act, rtilde));
  PetscCall(PetscFree(act));
  PetscCall(PetscTime(&t1));
  p->seconds = t1 - t0;
  PetscCall(PetscLogEventEnd(KERGS_Predict, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorView(KergsPredictor p, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(viewer, "Predictor: %s\n", p->type[0] ? p->type : "(not set)"));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  if (p->ops.view) PetscCall((*p->ops.view)(p, viewer));
  if (p->ksp) {
    PetscCall(PetscViewerASCIIPrintf(viewer, "DOF-space solver (prefix predictor_):\n"));
    PetscCall(PetscViewerASCIIPushTab(viewer));
    PetscCall(KSPView(p->ksp, viewer));
    PetscCall(PetscViewerASCIIPopTab(viewer));
  }
  PetscCall(PetscViewerASCIIPrintf(viewer, "last prediction: %" PetscInt_FMT " active contacts, %.3g s%s\n", p->nactive, (double)p->seconds,
                                   p->converged ? "" : " (not converged)"));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorSetOptionsPrefix(KergsPredictor p, const char prefix[])
{
  PetscFunctionBeginUser;
  PetscCall(PetscStrncpy(p->prefix, prefix ? prefix : "", sizeof(p->prefix)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorDestroy(KergsPredictor *p)
{
  PetscFunctionBeginUser;
  if (!*p) PetscFunctionReturn(0);
  if ((*p)->ops.destroy) PetscCall((*(*p)->ops.destroy)(*p));
  PetscCall(KSPDestroy(&(*p)->ksp));
  PetscCall(VecDestroy(&(*p)->Vtilde));
  PetscCall(PetscFree(*p));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPredictorGetStats(KergsPredictor p, KergsPredictorStats *st)
{
  PetscFunctionBeginUser;
  st->type        = p->type;
  st->seconds     = p->seconds;
  st->ksp_its     = p->ksp_its;
  st->sweeps      = p->sweeps;
  st->converged   = p->converged;
  st->nactive     = p->nactive;
  st->eta_abs     = p->eta_abs;
  st->epsilon_abs = p->epsilon_abs;
  PetscFunctionReturn(0);
}
