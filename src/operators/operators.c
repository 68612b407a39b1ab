/* kergs operators: H_f^T, H_g^T, M^-1, W = H_f^T M^-1 H_f, V_f, V_g, R^d and v^d for one step
   (docs/design.md: notation, parallel layout). Only what the scene needs is built: no rotations nor tangential
   components for a frictionless scene, no H_g without driven walls. */
#include <kergs/private/operatorsimpl.h>
#include <petscmat.h>

PetscErrorCode KergsOperatorsCreate(MPI_Comm comm, KergsOperators *ops)
{
  PetscFunctionBeginUser;
  PetscCall(PetscNew(ops));
  (*ops)->comm = comm;
  PetscFunctionReturn(0);
}

static PetscErrorCode DestroyStepObjects(KergsOperators ops)
{
  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsReleaseH(ops));
  PetscCall(KergsOperatorsReleaseW(ops));
  PetscCall(VecDestroy(&ops->vd));
  PetscCall(VecDestroy(&ops->r));
  PetscCall(VecDestroy(&ops->v));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsDestroy(KergsOperators *ops)
{
  PetscFunctionBeginUser;
  if (!*ops) PetscFunctionReturn(0);
  PetscCall(DestroyStepObjects(*ops));
  PetscCall(VecDestroy(&(*ops)->Minv));
  PetscCall(VecDestroy(&(*ops)->Vf));
  PetscCall(VecDestroy(&(*ops)->Rd));
  PetscCall(VecDestroy(&(*ops)->Vg));
  PetscCall(PetscFree((*ops)->wall_dof));
  PetscCall(PetscFree(*ops));
  PetscFunctionReturn(0);
}

/* DOF layout: disks by index (ndof_disk each), then free walls (KERGS_DIM each, on the last rank);
   driven walls' given DOFs all on rank 0. Vectors over DOFs are created once per scene size. */
static PetscErrorCode SetUpDofLayout(KergsOperators ops, KergsScene scene, const StepData *sd)
{
  PetscMPIInt rank, size;
  PetscInt    nfree_local, ngiven_local, nf = 0, ng = 0;
  PetscBool   frictional, rotating;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(ops->comm, &rank));
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  PetscCall(KergsSceneGetModel(scene, &frictional, &rotating));
  ops->ndof_disk = KERGS_DIM + (rotating ? KERGS_NROT : 0);
  ops->ncomp     = frictional ? KERGS_DIM : 1;
  PetscCall(PetscFree(ops->wall_dof));
  PetscCall(PetscMalloc1(sd->nwalls + 1, &ops->wall_dof));
  for (PetscInt w = 0; w < sd->nwalls; w++) {
    if (sd->walls[w].kind == KERGS_WALL_FREE)
      ops->wall_dof[w] = sd->D.ndisks * ops->ndof_disk + KERGS_DIM * nf++;
    else
      ops->wall_dof[w] = KERGS_DIM * ng++;
  }
  ops->nfreewalls   = nf;
  ops->ndrivenwalls = ng;
  ops->nfree        = sd->D.ndisks * ops->ndof_disk + KERGS_DIM * nf;
  ops->ngiven       = KERGS_DIM * ng;
  nfree_local       = (sd->D.dend - sd->D.dstart) * ops->ndof_disk + (rank == size - 1 ? KERGS_DIM * nf : 0);
  ngiven_local      = rank == 0 ? ops->ngiven : 0;
  {
    /* keep the DOF vectors only when no rank's layout changed (a renumbering may change some ranks only, and
       rebuilding is collective) */
    PetscInt changed = (PetscInt)(!ops->Vf || ops->nfree_local != nfree_local || ops->dstart != sd->D.dstart);
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &changed, 1, MPIU_INT, MPI_MAX, ops->comm));
    if (!changed) PetscFunctionReturn(0);
  }
  ops->nfree_local = nfree_local;
  ops->dstart      = sd->D.dstart;
  PetscCall(VecDestroy(&ops->Vf));
  PetscCall(VecDestroy(&ops->Minv));
  PetscCall(VecDestroy(&ops->Rd));
  PetscCall(VecDestroy(&ops->Vg));
  PetscCall(VecCreateMPI(ops->comm, nfree_local, ops->nfree, &ops->Vf));
  PetscCall(VecDuplicate(ops->Vf, &ops->Minv));
  PetscCall(VecDuplicate(ops->Vf, &ops->Rd));
  if (ng) PetscCall(VecCreateMPI(ops->comm, ngiven_local, ops->ngiven, &ops->Vg));
  PetscFunctionReturn(0);
}

/* M^-1, V_f^-, R^d (= dt * external forces) on the local free DOFs, V_g^+ on rank 0. Free walls feel
   their applied force only (no gravity), so that a pressure-controlled wall applies exactly that force. */
static PetscErrorCode SetDofVectors(KergsOperators ops, KergsScene scene, const StepData *sd)
{
  PetscScalar *minv, *vf, *rd;
  PetscInt     lo, hi, nd = ops->ndof_disk;
  PetscReal    time, dt, gravity[KERGS_DIM], tmid;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetStep(scene, NULL, &time, NULL));
  PetscCall(KergsSceneGetTimeStep(scene, &dt, NULL));
  PetscCall(KergsSceneGetGravity(scene, gravity));
  tmid = time + 0.5 * dt;
  PetscCall(VecGetOwnershipRange(ops->Vf, &lo, &hi));
  PetscCall(VecGetArray(ops->Minv, &minv));
  PetscCall(VecGetArray(ops->Vf, &vf));
  PetscCall(VecGetArray(ops->Rd, &rd));
  for (PetscInt i = 0; i < sd->D.nowned; i++) { /* owned disk i has global index dstart + i: its DOFs come first */
    PetscInt k = i * nd;
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      minv[k + d] = 1.0 / sd->D.mass[i];
      vf[k + d]   = sd->D.v[KERGS_DIM * i + d];
      rd[k + d]   = dt * sd->D.mass[i] * gravity[d];
    }
    for (PetscInt d = KERGS_DIM; d < nd; d++) {
      minv[k + d] = 1.0 / sd->D.inertia[i];
      vf[k + d]   = sd->D.omega[KERGS_NROT * i + d - KERGS_DIM];
      rd[k + d]   = 0.0;
    }
  }
  for (PetscInt w = 0; w < sd->nwalls; w++) {
    const KergsWall *wall = &sd->walls[w];
    PetscInt         k    = ops->wall_dof[w] - lo;
    if (wall->kind != KERGS_WALL_FREE || k < 0 || k >= hi - lo) continue;
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      minv[k + d] = 1.0 / wall->mass;
      vf[k + d]   = wall->v[d];
      rd[k + d]   = dt * wall->force[d];
    }
  }
  PetscCall(VecRestoreArray(ops->Minv, &minv));
  PetscCall(VecRestoreArray(ops->Vf, &vf));
  PetscCall(VecRestoreArray(ops->Rd, &rd));
  if (ops->Vg) {
    PetscScalar *vg;
    PetscInt     nglocal; /* rank 0 owns every given DOF, the others none */
    PetscCall(VecGetLocalSize(ops->Vg, &nglocal));
    PetscCall(VecGetArray(ops->Vg, &vg));
    for (PetscInt w = 0; w < sd->nwalls; w++) {
      PetscReal vw[KERGS_DIM];
      if (sd->walls[w].kind != KERGS_WALL_DRIVEN) continue;
      /* V_g^+ of the step: the program's value at mid-step, so that a piece boundary on a step boundary is exact */
      PetscCall(KergsWallVelocityAt(&sd->walls[w], tmid, vw));
      PetscCall(KergsSceneSetWallVelocity(scene, w, vw));
      if (nglocal)
        for (PetscInt d = 0; d < KERGS_DIM; d++) vg[ops->wall_dof[w] + d] = vw[d];
    }
    PetscCall(VecRestoreArray(ops->Vg, &vg));
  }
  PetscFunctionReturn(0);
}

static void AddBody(HtRow *row, PetscInt dof, PetscBool rotates, const PetscReal e[], PetscReal sign, PetscReal lever, PetscBool tangential)
{
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    row->col[row->ncol]   = dof + d;
    row->val[row->ncol++] = sign * e[d];
  }
  if (rotates && tangential) {
    row->col[row->ncol]   = dof + KERGS_DIM;
    row->val[row->ncol++] = -lever;
  }
}

/* A guided wall's DOFs see only the part of e along the wall's normal n: its row is -(e.n) n^T, so that W and the
   velocity update keep the wall on its guide. A contact at the wall's line has e = +-n or +-t (src/detect), so its
   tangential row is exactly zero; on an axis-aligned wall the DOF along the wall is then untouched to the bit. */
static void AddGuidedWall(HtRow *row, PetscInt dof, const KergsWall *wall, const PetscReal e[])
{
  PetscReal n[KERGS_DIM], en = 0.0;

  KergsWallNormal(wall, n);
  for (PetscInt d = 0; d < KERGS_DIM; d++) en += e[d] * n[d];
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    row->col[row->ncol]   = dof + d;
    row->val[row->ncol++] = -en * n[d];
  }
}

/* Entries of the rows of H^T for one contact: for component c, body a's columns get +e_c (and -ra for the
   tangential component on the rotation), body b's get -e_c (and -rb on its rotation) (docs/design.md, notation):
   v_n = n.(u_a - u_b), v_t = t.(u_a - u_b) - ra w_a - rb w_b. Row c (0 normal, 1 tangential) of contact ct, split
   into its free part (H_f^T) and given part (H_g^T). */
void KergsOperatorsContactRows(KergsOperators ops, const StepData *sd, const KergsContact *ct, PetscInt c, HtRow *free, HtRow *given)
{
  const PetscReal *e       = c == 0 ? ct->n : ct->t;
  PetscBool        rotates = (PetscBool)(ops->ndof_disk > KERGS_DIM);
  PetscBool        tang    = (PetscBool)(c > 0);

  free->ncol = given->ncol = 0;
  AddBody(free, KergsOperatorsDiskDof(ops, sd->D.gidx[ct->a]), rotates, e, 1.0, ct->ra, tang);
  if (ct->kind == KERGS_CONTACT_DISK_DISK)
    AddBody(free, KergsOperatorsDiskDof(ops, sd->D.gidx[ct->b]), rotates, e, -1.0, ct->rb, tang);
  else if (sd->walls[ct->b].kind == KERGS_WALL_FREE && sd->walls[ct->b].guided)
    AddGuidedWall(free, ops->wall_dof[ct->b], &sd->walls[ct->b], e);
  else if (sd->walls[ct->b].kind == KERGS_WALL_FREE)
    AddBody(free, ops->wall_dof[ct->b], PETSC_FALSE, e, -1.0, 0.0, tang);
  else
    AddBody(given, ops->wall_dof[ct->b], PETSC_FALSE, e, -1.0, 0.0, tang);
}

/* Create an AIJ Mat with exact preallocation: rows = local contact components, columns split at
   [clo, chi) into the diagonal and off-diagonal blocks. */
static PetscErrorCode CreateHt(KergsOperators ops, const StepData *sd, PetscBool freepart, PetscInt ncols_local, PetscInt ncols, Mat *Ht)
{
  PetscInt nrows = sd->ncontacts * ops->ncomp, *dnz, *onz, clo = 0;
  HtRow    fr, gr;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Exscan(&ncols_local, &clo, 1, MPIU_INT, MPI_SUM, ops->comm));
  PetscCall(PetscCalloc2(nrows, &dnz, nrows, &onz));
  for (PetscInt k = 0; k < sd->ncontacts; k++)
    for (PetscInt c = 0; c < ops->ncomp; c++) {
      HtRow *row = freepart ? &fr : &gr;
      KergsOperatorsContactRows(ops, sd, &sd->c[k], c, &fr, &gr);
      for (PetscInt j = 0; j < row->ncol; j++) {
        if (row->col[j] >= clo && row->col[j] < clo + ncols_local)
          dnz[k * ops->ncomp + c]++;
        else
          onz[k * ops->ncomp + c]++;
      }
    }
  PetscCall(MatCreate(ops->comm, Ht));
  PetscCall(MatSetSizes(*Ht, nrows, ncols_local, PETSC_DETERMINE, ncols));
  PetscCall(MatSetType(*Ht, MATAIJ));
  PetscCall(MatSeqAIJSetPreallocation(*Ht, 0, dnz));
  PetscCall(MatMPIAIJSetPreallocation(*Ht, 0, dnz, 0, onz));
  PetscCall(MatSetOption(*Ht, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(MatSetOption(*Ht, MAT_NO_OFF_PROC_ENTRIES, PETSC_TRUE));
  for (PetscInt k = 0; k < sd->ncontacts; k++)
    for (PetscInt c = 0; c < ops->ncomp; c++) {
      PetscInt row = (sd->start + k) * ops->ncomp + c;
      HtRow   *r   = freepart ? &fr : &gr;
      KergsOperatorsContactRows(ops, sd, &sd->c[k], c, &fr, &gr);
      if (r->ncol) PetscCall(MatSetValues(*Ht, 1, &row, r->ncol, r->col, r->val, INSERT_VALUES));
    }
  PetscCall(MatAssemblyBegin(*Ht, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Ht, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree2(dnz, onz));
  PetscFunctionReturn(0);
}

/* H_g^T: the given part of each contact's rows (NULL without driven walls). */
static PetscErrorCode BuildHg(KergsOperators ops, const StepData *sd)
{
  PetscInt nglocal;

  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&ops->HgT));
  if (!ops->ndrivenwalls) PetscFunctionReturn(0);
  PetscCall(VecGetLocalSize(ops->Vg, &nglocal));
  PetscCall(CreateHt(ops, sd, PETSC_FALSE, nglocal, ops->ngiven, &ops->HgT));
  PetscFunctionReturn(0);
}

static PetscErrorCode BuildHf(KergsOperators ops, const StepData *sd)
{
  MatInfo info;

  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&ops->HfT));
  PetscCall(CreateHt(ops, sd, PETSC_TRUE, ops->nfree_local, ops->nfree, &ops->HfT));
  PetscCall(MatGetInfo(ops->HfT, MAT_GLOBAL_SUM, &info));
  ops->nnz_Hf = info.nz_used;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsBuildHf(KergsOperators ops, KergsScene scene, KergsContacts contacts)
{
  StepData sd;

  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsGetStepData(ops, scene, contacts, &sd));
  PetscCall(BuildHf(ops, &sd));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsReleaseH(KergsOperators ops)
{
  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&ops->HfT));
  PetscCall(MatDestroy(&ops->HgT));
  PetscFunctionReturn(0);
}

/* v^d = H_g^T V_g^+ + H_f^T (V_f^- + M^-1 R^d), with r and v of the same layout. H_g^T comes and, unless kept, goes
   before H_f^T is built, so that the two coexist only when kept. */
PetscErrorCode KergsOperatorsAssembleH(KergsOperators ops, KergsScene scene, KergsContacts contacts, PetscBool keep)
{
  StepData stepdata, *sd = &stepdata;
  Vec      tmp;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(KERGS_Assemble, 0, 0, 0, 0));
  PetscCall(DestroyStepObjects(ops));
  PetscCall(KergsOperatorsGetStepData(ops, scene, contacts, sd));
  PetscCall(SetUpDofLayout(ops, scene, sd));
  PetscCall(SetDofVectors(ops, scene, sd));
  PetscCall(VecCreateMPI(ops->comm, sd->ncontacts * ops->ncomp, PETSC_DETERMINE, &ops->vd));
  PetscCall(VecDuplicate(ops->vd, &ops->r));
  PetscCall(VecDuplicate(ops->vd, &ops->v));
  PetscCall(BuildHg(ops, sd));
  if (ops->HgT)
    PetscCall(MatMult(ops->HgT, ops->Vg, ops->vd));
  else
    PetscCall(VecZeroEntries(ops->vd));
  if (!keep) PetscCall(MatDestroy(&ops->HgT));
  PetscCall(BuildHf(ops, sd));
  PetscCall(VecDuplicate(ops->Vf, &tmp));
  PetscCall(VecPointwiseMult(tmp, ops->Minv, ops->Rd));
  PetscCall(VecAXPY(tmp, 1.0, ops->Vf));
  PetscCall(MatMultAdd(ops->HfT, tmp, ops->vd, ops->vd));
  PetscCall(VecDestroy(&tmp));
  if (!keep) PetscCall(KergsOperatorsReleaseH(ops));
  PetscCall(PetscLogEventEnd(KERGS_Assemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsAssemble(KergsOperators ops, KergsScene scene, KergsContacts contacts)
{
  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsAssembleH(ops, scene, contacts, PETSC_TRUE));
  PetscCall(KergsOperatorsAssembleW(ops, scene, contacts, PETSC_FALSE));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetFullW(KergsOperators ops, Mat *Wfull)
{
  PetscFunctionBeginUser;
  if (ops->Wboth) { /* assembled with W (several ranks) */
    PetscCall(PetscObjectReference((PetscObject)ops->Wboth));
    *Wfull = ops->Wboth;
    PetscFunctionReturn(0);
  }
  /* from SBAIJ, PETSc's conversion writes W_beta,alpha = W_alpha,beta^T below the diagonal */
  PetscCall(MatConvert(ops->W, ops->ncomp > 1 ? MATBAIJ : MATAIJ, MAT_INITIAL_MATRIX, Wfull));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsSetBothTriangles(KergsOperators ops, PetscBool both)
{
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  ops->both_triangles = (PetscBool)(both && size > 1);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetImpulses(KergsOperators ops, KergsContacts contacts)
{
  PetscScalar  *r;
  KergsContact *c;
  PetscInt      n;

  PetscFunctionBeginUser;
  PetscCall(KergsContactsGetLocal(contacts, &n, &c));
  PetscCall(VecGetArray(ops->r, &r));
  for (PetscInt k = 0; k < n; k++)
    for (PetscInt j = 0; j < ops->ncomp; j++) r[k * ops->ncomp + j] = c[k].r[j];
  PetscCall(VecRestoreArray(ops->r, &r));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsSetImpulses(KergsOperators ops, KergsContacts contacts)
{
  const PetscScalar *r;
  KergsContact      *c;
  PetscInt           n;

  PetscFunctionBeginUser;
  PetscCall(KergsContactsGetLocal(contacts, &n, &c));
  PetscCall(VecGetArrayRead(ops->r, &r));
  for (PetscInt k = 0; k < n; k++) {
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) c[k].r[j] = 0.0;
    for (PetscInt j = 0; j < ops->ncomp; j++) c[k].r[j] = r[k * ops->ncomp + j];
  }
  PetscCall(VecRestoreArrayRead(ops->r, &r));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsUpdateVelocities(KergsOperators ops, KergsScene scene)
{
  const PetscScalar *vf;
  PetscInt           nd = ops->ndof_disk, lo, nwalls;
  const KergsWall   *walls;
  KergsDisks         D;
  PetscMPIInt        size;
  Vec                R;

  PetscFunctionBeginUser;
  PetscCheck(ops->HfT, ops->comm, PETSC_ERR_ORDER, "KergsOperatorsUpdateVelocities: H_f was released; call KergsOperatorsBuildHf first");
  /* V_f^+ = V_f^- + M^-1 (H_f r + R^d) */
  PetscCall(VecDuplicate(ops->Vf, &R));
  PetscCall(MatMultTransposeAdd(ops->HfT, ops->r, ops->Rd, R));
  PetscCall(VecPointwiseMult(R, R, ops->Minv));
  PetscCall(VecAXPY(ops->Vf, 1.0, R));
  PetscCall(VecDestroy(&R));
  /* each rank's V_f holds its own disks' DOFs: copy them into the owned disks (ghosts follow in
     KergsSceneRefreshGhosts) */
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetWalls(scene, &nwalls, &walls));
  PetscCall(VecGetOwnershipRange(ops->Vf, &lo, NULL));
  PetscCall(VecGetArrayRead(ops->Vf, &vf));
  for (PetscInt i = 0; i < D.nowned; i++) {
    for (PetscInt d = 0; d < KERGS_DIM; d++) D.v[KERGS_DIM * i + d] = vf[i * nd + d];
    for (PetscInt d = KERGS_DIM; d < nd; d++) D.omega[KERGS_NROT * i + d - KERGS_DIM] = vf[i * nd + d];
  }
  /* free walls live on the last rank: every rank gets their velocities (KERGS_DIM values per wall) */
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  for (PetscInt w = 0; w < nwalls; w++) {
    PetscInt  k = ops->wall_dof[w] - lo;
    PetscReal vw[KERGS_DIM];
    if (walls[w].kind != KERGS_WALL_FREE) continue;
    for (PetscInt d = 0; d < KERGS_DIM; d++) vw[d] = k >= 0 && k < ops->nfree_local ? vf[k + d] : walls[w].v[d];
    PetscCallMPI(MPI_Bcast(vw, KERGS_DIM, MPIU_REAL, size - 1, ops->comm));
    /* on an oblique guided wall the update's two components round differently: keep the velocity on the normal, or
       the rounding along the wall accumulates over the steps */
    if (walls[w].guided) KergsWallOnNormal(&walls[w], vw);
    PetscCall(KergsSceneSetWallVelocity(scene, w, vw));
  }
  PetscCall(VecRestoreArrayRead(ops->Vf, &vf));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Accessors                                                                                        */

PetscErrorCode KergsOperatorsGetStepData(KergsOperators ops, KergsScene scene, KergsContacts contacts, StepData *sd)
{
  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(scene, &sd->D));
  PetscCall(KergsSceneGetWalls(scene, &sd->nwalls, &sd->walls));
  PetscCall(KergsContactsGetLocal(contacts, &sd->ncontacts, &sd->c));
  PetscCall(KergsContactsGetForeign(contacts, &sd->nforeign, &sd->foreign, &sd->foreign_index));
  PetscCall(KergsContactsGetGlobalRange(contacts, &sd->start, NULL));
  PetscCall(KergsContactsGetActivity(contacts, scene, &sd->activity));
  (void)ops;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetLayout(KergsOperators ops, KergsDofLayout *layout)
{
  PetscFunctionBeginUser;
  layout->ncomp        = ops->ncomp;
  layout->ndof_disk    = ops->ndof_disk;
  layout->ndisks       = ops->ndof_disk ? (ops->nfree - KERGS_DIM * ops->nfreewalls) / ops->ndof_disk : 0;
  layout->nfreewalls   = ops->nfreewalls;
  layout->ndrivenwalls = ops->ndrivenwalls;
  layout->nfree        = ops->nfree;
  layout->nfree_local  = ops->nfree_local;
  layout->ngiven       = ops->ngiven;
  layout->wall_dof     = ops->wall_dof;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetContactVectors(KergsOperators ops, Vec *r, Vec *v, Vec *vd)
{
  PetscFunctionBeginUser;
  if (r) *r = ops->r;
  if (v) *v = ops->v;
  if (vd) *vd = ops->vd;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetDofVectors(KergsOperators ops, Vec *Vf, Vec *Minv, Vec *Rd, Vec *Vg)
{
  PetscFunctionBeginUser;
  if (Vf) *Vf = ops->Vf;
  if (Minv) *Minv = ops->Minv;
  if (Rd) *Rd = ops->Rd;
  if (Vg) *Vg = ops->Vg;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetH(KergsOperators ops, Mat *HfT, Mat *HgT)
{
  PetscFunctionBeginUser;
  if (HfT) *HfT = ops->HfT;
  if (HgT) *HgT = ops->HgT;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetW(KergsOperators ops, Mat *W, PetscBool *active_only)
{
  PetscFunctionBeginUser;
  if (W) *W = ops->W;
  if (active_only) *active_only = ops->W_active_only;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetNonzeros(KergsOperators ops, PetscReal *nnz_Hf, PetscReal *nnz_W)
{
  PetscFunctionBeginUser;
  if (nnz_Hf) *nnz_Hf = ops->nnz_Hf;
  if (nnz_W) *nnz_W = ops->nnz_W;
  PetscFunctionReturn(0);
}
