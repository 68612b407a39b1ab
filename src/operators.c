/* kergs operators: H_f^T, H_g^T, M^-1, W = H_f^T M^-1 H_f, V_f, V_g, R^d and v^d for one step
   (DESIGN.md sections 2 and 6). Only what the scene needs is built: no rotations nor tangential
   components for a frictionless scene, no H_g without driven walls. */
#include <kergs/operators.h>
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
  PetscCall(MatDestroy(&ops->HfT));
  PetscCall(MatDestroy(&ops->Hf));
  PetscCall(MatDestroy(&ops->HgT));
  PetscCall(MatDestroy(&ops->W));
  PetscCall(VecDestroy(&ops->vd));
  PetscCall(VecDestroy(&ops->vminus));
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
  PetscCall(VecDestroy(&(*ops)->R));
  PetscCall(VecDestroy(&(*ops)->Vg));
  PetscCall(PetscFree((*ops)->wall_dof));
  PetscCall(PetscFree(*ops));
  PetscFunctionReturn(0);
}

/* DOF layout: disks by index (ndof_disk each), then free walls (KERGS_DIM each, on the last rank);
   driven walls' given DOFs all on rank 0. Vectors over DOFs are created once per scene size. */
static PetscErrorCode SetUpDofLayout(KergsOperators ops, KergsScene scene)
{
  PetscMPIInt rank, size;
  PetscInt    nfree_local, ngiven_local, nf = 0, ng = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(ops->comm, &rank));
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  ops->ndof_disk = KERGS_DIM + (scene->frictional && !scene->lock_rotation ? KERGS_NROT : 0);
  ops->ncomp     = scene->frictional ? KERGS_DIM : 1;
  PetscCall(PetscFree(ops->wall_dof));
  PetscCall(PetscMalloc1(scene->nwalls + 1, &ops->wall_dof));
  for (PetscInt w = 0; w < scene->nwalls; w++) {
    if (scene->walls[w].kind == KERGS_WALL_FREE) ops->wall_dof[w] = scene->ndisks * ops->ndof_disk + KERGS_DIM * nf++;
    else ops->wall_dof[w] = KERGS_DIM * ng++;
  }
  ops->nfreewalls   = nf;
  ops->ndrivenwalls = ng;
  ops->nfree        = scene->ndisks * ops->ndof_disk + KERGS_DIM * nf;
  ops->ngiven       = KERGS_DIM * ng;
  nfree_local       = (scene->dend - scene->dstart) * ops->ndof_disk + (rank == size - 1 ? KERGS_DIM * nf : 0);
  ngiven_local      = rank == 0 ? ops->ngiven : 0;
  {
    /* keep the DOF vectors only when no rank's layout changed (a renumbering may change some ranks only, and
       rebuilding is collective) */
    PetscInt changed = (PetscInt)(!ops->Vf || ops->nfree_local != nfree_local || ops->dstart != scene->dstart);
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &changed, 1, MPIU_INT, MPI_MAX, ops->comm));
    if (!changed) PetscFunctionReturn(0);
  }
  ops->nfree_local = nfree_local;
  ops->dstart      = scene->dstart;
  PetscCall(VecDestroy(&ops->Vf));
  PetscCall(VecDestroy(&ops->Minv));
  PetscCall(VecDestroy(&ops->Rd));
  PetscCall(VecDestroy(&ops->R));
  PetscCall(VecDestroy(&ops->Vg));
  PetscCall(VecCreateMPI(ops->comm, nfree_local, ops->nfree, &ops->Vf));
  PetscCall(VecDuplicate(ops->Vf, &ops->Minv));
  PetscCall(VecDuplicate(ops->Vf, &ops->Rd));
  PetscCall(VecDuplicate(ops->Vf, &ops->R));
  if (ng) PetscCall(VecCreateMPI(ops->comm, ngiven_local, ops->ngiven, &ops->Vg));
  PetscFunctionReturn(0);
}

/* M^-1, V_f^-, R^d (= dt * external forces) on the local free DOFs, V_g^+ on rank 0. Free walls feel
   their applied force only (no gravity), so that a pressure-controlled wall applies exactly that force. */
static PetscErrorCode SetDofVectors(KergsOperators ops, KergsScene scene)
{
  PetscScalar *minv, *vf, *rd;
  PetscInt     lo, hi, nd = ops->ndof_disk;
  PetscReal    tmid = scene->time + 0.5 * scene->dt;

  PetscFunctionBeginUser;
  PetscCall(VecGetOwnershipRange(ops->Vf, &lo, &hi));
  PetscCall(VecGetArray(ops->Minv, &minv));
  PetscCall(VecGetArray(ops->Vf, &vf));
  PetscCall(VecGetArray(ops->Rd, &rd));
  for (PetscInt i = 0; i < scene->nowned; i++) { /* owned disk i has global index dstart + i: its DOFs come first */
    PetscInt k = i * nd;
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      minv[k + d] = 1.0 / scene->mass[i];
      vf[k + d]   = scene->v[KERGS_DIM * i + d];
      rd[k + d]   = scene->dt * scene->mass[i] * scene->gravity[d];
    }
    for (PetscInt d = KERGS_DIM; d < nd; d++) {
      minv[k + d] = 1.0 / scene->inertia[i];
      vf[k + d]   = scene->omega[KERGS_NROT * i + d - KERGS_DIM];
      rd[k + d]   = 0.0;
    }
  }
  for (PetscInt w = 0; w < scene->nwalls; w++) {
    const KergsWall *wall = &scene->walls[w];
    PetscInt         k    = ops->wall_dof[w] - lo;
    if (wall->kind != KERGS_WALL_FREE || k < 0 || k >= hi - lo) continue;
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      minv[k + d] = 1.0 / wall->mass;
      vf[k + d]   = wall->v[d];
      rd[k + d]   = scene->dt * wall->force[d];
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
    for (PetscInt w = 0; w < scene->nwalls; w++) {
      KergsWall *wall = &scene->walls[w];
      if (wall->kind != KERGS_WALL_DRIVEN) continue;
      /* V_g^+ of the step: the program's value at mid-step, so that a piece boundary on a step boundary is exact */
      PetscCall(KergsWallVelocityAt(wall, tmid, wall->v));
      if (nglocal)
        for (PetscInt d = 0; d < KERGS_DIM; d++) vg[ops->wall_dof[w] + d] = wall->v[d];
    }
    PetscCall(VecRestoreArray(ops->Vg, &vg));
  }
  PetscFunctionReturn(0);
}

/* Entries of the rows of H^T for one contact: for component c, body a's columns get +e_c (and -ra for the
   tangential component on the rotation), body b's get -e_c (and -rb on its rotation); DESIGN.md section 2:
   v_n = n.(u_a - u_b), v_t = t.(u_a - u_b) - ra w_a - rb w_b. */
typedef struct {
  PetscInt  ncol;
  PetscInt  col[2 * (KERGS_DIM + KERGS_NROT)];
  PetscReal val[2 * (KERGS_DIM + KERGS_NROT)];
} HtRow;

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

/* Row c (0 normal, 1 tangential) of contact k, split into its free part (H_f^T) and given part (H_g^T). */
static void ContactRows(KergsOperators ops, KergsScene scene, const KergsContact *ct, PetscInt c, HtRow *free, HtRow *given)
{
  const PetscReal *e       = c == 0 ? ct->n : ct->t;
  PetscBool        rotates = (PetscBool)(ops->ndof_disk > KERGS_DIM);
  PetscBool        tang    = (PetscBool)(c > 0);

  free->ncol = given->ncol = 0;
  AddBody(free, KergsOperatorsDiskDof(ops, scene->gidx[ct->a]), rotates, e, 1.0, ct->ra, tang);
  if (ct->kind == KERGS_CONTACT_DISK_DISK) AddBody(free, KergsOperatorsDiskDof(ops, scene->gidx[ct->b]), rotates, e, -1.0, ct->rb, tang);
  else if (scene->walls[ct->b].kind == KERGS_WALL_FREE) AddBody(free, ops->wall_dof[ct->b], PETSC_FALSE, e, -1.0, 0.0, tang);
  else AddBody(given, ops->wall_dof[ct->b], PETSC_FALSE, e, -1.0, 0.0, tang);
}

/* Create an AIJ Mat with exact preallocation: rows = local contact components, columns split at
   [clo, chi) into the diagonal and off-diagonal blocks. */
static PetscErrorCode CreateHt(KergsOperators ops, KergsScene scene, KergsContacts contacts, PetscBool freepart, PetscInt ncols_local,
                               PetscInt ncols, Mat *Ht)
{
  PetscInt  nrows = contacts->n * ops->ncomp, *dnz, *onz, clo = 0;
  HtRow     fr, gr;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Exscan(&ncols_local, &clo, 1, MPIU_INT, MPI_SUM, ops->comm));
  PetscCall(PetscCalloc2(nrows, &dnz, nrows, &onz));
  for (PetscInt k = 0; k < contacts->n; k++)
    for (PetscInt c = 0; c < ops->ncomp; c++) {
      HtRow *row = freepart ? &fr : &gr;
      ContactRows(ops, scene, &contacts->c[k], c, &fr, &gr);
      for (PetscInt j = 0; j < row->ncol; j++) {
        if (row->col[j] >= clo && row->col[j] < clo + ncols_local) dnz[k * ops->ncomp + c]++;
        else onz[k * ops->ncomp + c]++;
      }
    }
  PetscCall(MatCreate(ops->comm, Ht));
  PetscCall(MatSetSizes(*Ht, nrows, ncols_local, PETSC_DETERMINE, ncols));
  PetscCall(MatSetType(*Ht, MATAIJ));
  PetscCall(MatSeqAIJSetPreallocation(*Ht, 0, dnz));
  PetscCall(MatMPIAIJSetPreallocation(*Ht, 0, dnz, 0, onz));
  PetscCall(MatSetOption(*Ht, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(MatSetOption(*Ht, MAT_NO_OFF_PROC_ENTRIES, PETSC_TRUE));
  for (PetscInt k = 0; k < contacts->n; k++)
    for (PetscInt c = 0; c < ops->ncomp; c++) {
      PetscInt row = (contacts->start + k) * ops->ncomp + c;
      HtRow   *r   = freepart ? &fr : &gr;
      ContactRows(ops, scene, &contacts->c[k], c, &fr, &gr);
      if (r->ncol) PetscCall(MatSetValues(*Ht, 1, &row, r->ncol, r->col, r->val, INSERT_VALUES));
    }
  PetscCall(MatAssemblyBegin(*Ht, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Ht, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree2(dnz, onz));
  PetscFunctionReturn(0);
}

/* bcol[0 .. nb) (sorted, distinct) merged with the block columns cols[]/nc of one sorted row, through tmp;
   returns the new count. Linear: the rows come sorted from MatGetRow. */
static PetscInt MergeBlockColumns(PetscInt nb, PetscInt *bcol, PetscInt ncols, const PetscInt *cols, PetscInt nc, PetscInt *tmp)
{
  PetscInt i = 0, j = 0, n = 0, b;

  while (i < nb || j < ncols) {
    if (j == ncols || (i < nb && bcol[i] <= cols[j] / nc)) b = bcol[i++];
    else b = cols[j++] / nc;
    if (!n || tmp[n - 1] != b) tmp[n++] = b;
  }
  for (i = 0; i < n; i++) bcol[i] = tmp[i];
  return n;
}

/* The block columns of block row a (global contact indices, sorted, distinct) of an AIJ W with nc rows per
   contact: the columns of rows a*nc .. a*nc+nc-1, divided by nc, merged into bcol[]; returns their number. */
static PetscErrorCode BlockColumns(Mat W, PetscInt nc, PetscInt a, PetscInt *bcol, PetscInt *tmp, PetscInt *nb)
{
  const PetscInt *cols;
  PetscInt        ncols, row;

  PetscFunctionBeginUser;
  *nb = 0;
  for (PetscInt c = 0; c < nc; c++) {
    row = a * nc + c;
    PetscCall(MatGetRow(W, row, &ncols, &cols, NULL));
    *nb = MergeBlockColumns(*nb, bcol, ncols, cols, nc, tmp);
    PetscCall(MatRestoreRow(W, row, &ncols, &cols, NULL));
  }
  PetscFunctionReturn(0);
}

/* The block row a of an AIJ W, row-major as MatSetValuesBlocked takes it: entry (c, b*nc + e) is
   W_(a nc + c),(bcol[b] nc + e), zero where the AIJ row has no entry. A row's sorted columns walk bcol once. */
static PetscErrorCode BlockRowValues(Mat W, PetscInt nc, PetscInt a, const PetscInt *bcol, PetscInt nb, PetscScalar *vals)
{
  const PetscInt    *cols;
  const PetscScalar *v;
  PetscInt           ncols, row, b;

  PetscFunctionBeginUser;
  PetscCall(PetscArrayzero(vals, nc * nb * nc));
  for (PetscInt c = 0; c < nc; c++) {
    row = a * nc + c;
    PetscCall(MatGetRow(W, row, &ncols, &cols, &v));
    b = 0;
    for (PetscInt j = 0; j < ncols; j++) {
      while (bcol[b] < cols[j] / nc) b++;
      vals[(c * nb + b) * nc + cols[j] % nc] = v[j];
    }
    PetscCall(MatRestoreRow(W, row, &ncols, &cols, &v));
  }
  PetscFunctionReturn(0);
}

/* Several ranks: the MPIAIJ product W re-stored as MPIBAIJ with block size nc, preallocated exactly by block
   and filled a block row at a time (MatConvert in PETSc 3.18, entry by entry, took 4.8 s per step on biaxial
   20k with 2 ranks against 0.04 s here). Both copies exist until the AIJ one is destroyed. */
static PetscErrorCode ConvertToBlocks(Mat *W, PetscInt nc)
{
  Mat          Wb;
  PetscInt     m, M, rstart, rend, n, *dnz, *onz, *bcol, *tmp, nb, maxcols = 0, ncols;
  PetscScalar *vals;

  PetscFunctionBeginUser;
  PetscCall(MatGetLocalSize(*W, &m, NULL));
  PetscCall(MatGetSize(*W, &M, NULL));
  PetscCall(MatGetOwnershipRange(*W, &rstart, &rend));
  n = m / nc;
  for (PetscInt i = rstart; i < rend; i++) {
    PetscCall(MatGetRow(*W, i, &ncols, NULL, NULL));
    maxcols = PetscMax(maxcols, ncols);
    PetscCall(MatRestoreRow(*W, i, &ncols, NULL, NULL));
  }
  PetscCall(PetscMalloc5(n, &dnz, n, &onz, nc * maxcols, &bcol, nc * maxcols, &tmp, nc * nc * nc * maxcols, &vals));
  for (PetscInt a = 0; a < n; a++) {
    PetscCall(BlockColumns(*W, nc, rstart / nc + a, bcol, tmp, &nb));
    dnz[a] = onz[a] = 0;
    for (PetscInt b = 0; b < nb; b++) {
      if (bcol[b] >= rstart / nc && bcol[b] < rend / nc) dnz[a]++;
      else onz[a]++;
    }
  }
  PetscCall(MatCreateBAIJ(PetscObjectComm((PetscObject)*W), nc, m, m, M, M, 0, dnz, 0, onz, &Wb));
  PetscCall(MatSetOption(Wb, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  for (PetscInt a = rstart / nc; a < rend / nc; a++) {
    PetscCall(BlockColumns(*W, nc, a, bcol, tmp, &nb));
    PetscCall(BlockRowValues(*W, nc, a, bcol, nb, vals));
    PetscCall(MatSetValuesBlocked(Wb, 1, &a, nb, bcol, vals, INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(Wb, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(Wb, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree5(dnz, onz, bcol, tmp, vals));
  PetscCall(MatDestroy(W));
  *W = Wb;
  PetscFunctionReturn(0);
}

/* Several ranks: W = H_f^T (M^-1 H_f) by PETSc's parallel product, since a rank does not know the other ranks'
   contacts that share its bodies. H_f is the explicit transpose of H_f^T, its rows scaled in place by the
   diagonal M^-1, then an A B product with the "scalable" algorithm (no transpose of the second factor, as
   A B^T would keep). MatProductClear drops the intermediate data and the references to the factors at once,
   and M^-1 H_f is freed before the product is re-stored as MPIBAIJ with block size ncomp (one column index per
   block, as the sweep reads it); the conversion holds both copies of W for a moment. KergsOperatorsGetHf rebuilds H_f unscaled on demand. */
static PetscErrorCode ComputeDelassusProduct(KergsOperators ops)
{
  Mat MinvHf;

  PetscFunctionBeginUser;
  PetscCall(MatTranspose(ops->HfT, MAT_INITIAL_MATRIX, &MinvHf));
  PetscCall(MatDiagonalScale(MinvHf, ops->Minv, NULL));
  PetscCall(MatProductCreate(ops->HfT, MinvHf, NULL, &ops->W));
  PetscCall(MatProductSetType(ops->W, MATPRODUCT_AB));
  PetscCall(MatProductSetAlgorithm(ops->W, "scalable"));
  PetscCall(MatProductSetFill(ops->W, PETSC_DEFAULT));
  PetscCall(MatProductSetFromOptions(ops->W));
  PetscCall(MatProductSymbolic(ops->W));
  PetscCall(MatProductNumeric(ops->W));
  PetscCall(MatProductClear(ops->W));
  PetscCall(MatDestroy(&MinvHf));
  if (ops->ncomp > 1) PetscCall(ConvertToBlocks(&ops->W, ops->ncomp));
  PetscFunctionReturn(0);
}

/* The free bodies of a contact, numbered disks first (0 .. ndisks-1) then walls (ndisks + w); -1 for a driven
   wall, whose DOFs are given (H_g), not free. */
static void ContactBodies(KergsScene scene, const KergsContact *ct, PetscInt body[2])
{
  body[0] = ct->a;
  if (ct->kind == KERGS_CONTACT_DISK_DISK) body[1] = ct->b;
  else body[1] = scene->walls[ct->b].kind == KERGS_WALL_FREE ? scene->ndisks + ct->b : -1;
}

/* The contacts touching each free body, in CSR form: those of body q are list[start[q] .. start[q+1]), in
   increasing order. This is the sparsity of H_f by blocks, at about one integer per contact end. */
static PetscErrorCode BodyContacts(KergsScene scene, KergsContacts contacts, PetscInt **start, PetscInt **list)
{
  const PetscInt nb = scene->ndisks + scene->nwalls;
  PetscInt       body[2], *fill;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(nb + 1, start));
  for (PetscInt k = 0; k < contacts->n; k++) {
    ContactBodies(scene, &contacts->c[k], body);
    for (PetscInt e = 0; e < 2; e++)
      if (body[e] >= 0) (*start)[body[e] + 1]++;
  }
  for (PetscInt q = 0; q < nb; q++) (*start)[q + 1] += (*start)[q];
  PetscCall(PetscMalloc1((*start)[nb], list));
  PetscCall(PetscMalloc1(nb, &fill));
  PetscCall(PetscArraycpy(fill, *start, nb));
  for (PetscInt k = 0; k < contacts->n; k++) {
    ContactBodies(scene, &contacts->c[k], body);
    for (PetscInt e = 0; e < 2; e++)
      if (body[e] >= 0) (*list)[fill[body[e]]++] = k;
  }
  PetscCall(PetscFree(fill));
  PetscFunctionReturn(0);
}

/* The contacts coupled to contact k in W (those sharing a free body with it, k included), sorted, into nb[];
   returns their number. mark[] (one per contact, -1 on entry) is left as it was found. */
static PetscInt CoupledContacts(KergsScene scene, KergsContacts contacts, const PetscInt *start, const PetscInt *list, PetscInt k, PetscInt *mark,
                                PetscInt *nb)
{
  PetscInt body[2], n = 0;

  ContactBodies(scene, &contacts->c[k], body);
  for (PetscInt e = 0; e < 2; e++) {
    if (body[e] < 0) continue;
    for (PetscInt j = start[body[e]]; j < start[body[e] + 1]; j++)
      if (mark[list[j]] != k) {
        mark[list[j]] = k;
        nb[n++]       = list[j];
      }
  }
  for (PetscInt j = 0; j < n; j++) mark[nb[j]] = -1;
  (void)PetscSortInt(n, nb);
  return n;
}

/* W_ij = sum_d (H_f^T)_id (M^-1)_d (H_f^T)_jd, a merge of the two sorted rows i and j of H_f^T. */
static PetscScalar RowProduct(const PetscInt *ai, const PetscInt *aj, const PetscScalar *aa, const PetscScalar *minv, PetscInt i, PetscInt j)
{
  PetscInt    p = ai[i], q = ai[j];
  PetscScalar w = 0.0;

  while (p < ai[i + 1] && q < ai[j + 1]) {
    if (aj[p] < aj[q]) p++;
    else if (aj[p] > aj[q]) q++;
    else {
      w += aa[p] * minv[aj[p]] * aa[q];
      p++;
      q++;
    }
  }
  return w;
}

/* The block row of contact k, [W_k,nb[0] ... W_k,nb[m-1]], row-major as MatSetValuesBlocked takes it: the
   entry (c, b*nc + e) is W_(k nc + c),(nb[b] nc + e). */
static void BlockRow(const PetscInt *ai, const PetscInt *aj, const PetscScalar *aa, const PetscScalar *minv, PetscInt nc, PetscInt k, PetscInt m,
                     const PetscInt *nb, PetscScalar *vals)
{
  for (PetscInt c = 0; c < nc; c++)
    for (PetscInt b = 0; b < m; b++)
      for (PetscInt e = 0; e < nc; e++) vals[(c * m + b) * nc + e] = RowProduct(ai, aj, aa, minv, k * nc + c, nb[b] * nc + e);
}

/* One rank: W assembled directly from its definition, W_ij = sum_d (H_f^T)_id (M^-1)_d (H_f^T)_jd. Contacts
   alpha and beta are coupled iff they share a free body, so the body-to-contacts incidence gives W's
   sparsity exactly: W is preallocated to the block, and nothing of the size of W or H_f is built on the side
   (a general sparse product would hold H_f and a growing copy of W's column indices). W is stored by
   ncomp x ncomp blocks, one block row per contact (BAIJ; AIJ when ncomp = 1), so that a block W_alpha,beta
   carries one column index. */
static PetscErrorCode ComputeDelassusSeq(KergsOperators ops, KergsScene scene, KergsContacts contacts)
{
  const PetscInt     nc = ops->ncomp, n = contacts->n;
  PetscInt          *start, *list, *mark, *bnnz, *nb, maxnb = 0, nrow;
  const PetscInt    *ai, *aj;
  const PetscScalar *aa, *minv;
  PetscScalar       *vals;
  PetscBool          done;

  PetscFunctionBeginUser;
  PetscCall(BodyContacts(scene, contacts, &start, &list));
  PetscCall(PetscMalloc2(n, &mark, n, &bnnz));
  for (PetscInt q = 0; q < scene->ndisks + scene->nwalls; q++) maxnb = PetscMax(maxnb, start[q + 1] - start[q]);
  maxnb = PetscMin(2 * maxnb, n); /* a contact touches at most two bodies */
  PetscCall(PetscMalloc2(maxnb, &nb, maxnb * nc * nc, &vals));
  for (PetscInt k = 0; k < n; k++) mark[k] = -1;
  for (PetscInt k = 0; k < n; k++) bnnz[k] = CoupledContacts(scene, contacts, start, list, k, mark, nb);
  PetscCall(MatCreate(ops->comm, &ops->W));
  PetscCall(MatSetSizes(ops->W, n * nc, n * nc, n * nc, n * nc));
  PetscCall(MatSetBlockSize(ops->W, nc));
  PetscCall(MatSetType(ops->W, nc > 1 ? MATSEQBAIJ : MATSEQAIJ));
  PetscCall(MatXAIJSetPreallocation(ops->W, nc, bnnz, NULL, NULL, NULL));
  PetscCall(MatSetOption(ops->W, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(MatGetRowIJ(ops->HfT, 0, PETSC_FALSE, PETSC_FALSE, &nrow, &ai, &aj, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "ComputeDelassusSeq: no CSR arrays for H_f^T");
  PetscCall(MatSeqAIJGetArrayRead(ops->HfT, &aa));
  PetscCall(VecGetArrayRead(ops->Minv, &minv));
  for (PetscInt k = 0; k < n; k++) {
    const PetscInt m = CoupledContacts(scene, contacts, start, list, k, mark, nb);
    BlockRow(ai, aj, aa, minv, nc, k, m, nb, vals);
    PetscCall(MatSetValuesBlocked(ops->W, 1, &k, m, nb, vals, INSERT_VALUES));
  }
  PetscCall(VecRestoreArrayRead(ops->Minv, &minv));
  PetscCall(MatSeqAIJRestoreArrayRead(ops->HfT, &aa));
  PetscCall(MatRestoreRowIJ(ops->HfT, 0, PETSC_FALSE, PETSC_FALSE, &nrow, &ai, &aj, &done));
  PetscCall(MatAssemblyBegin(ops->W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ops->W, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree2(nb, vals));
  PetscCall(PetscFree2(mark, bnnz));
  PetscCall(PetscFree(start));
  PetscCall(PetscFree(list));
  PetscFunctionReturn(0);
}

static PetscErrorCode ComputeDelassus(KergsOperators ops, KergsScene scene, KergsContacts contacts)
{
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  if (size == 1) PetscCall(ComputeDelassusSeq(ops, scene, contacts));
  else PetscCall(ComputeDelassusProduct(ops));
  PetscFunctionReturn(0);
}

/* v^d = H_f^T (V_f^- + M^-1 R^d) + H_g^T V_g^+, and v^- = H_f^T V_f^- + H_g^T V_g^+. */
static PetscErrorCode ComputeFreeVelocity(KergsOperators ops)
{
  Vec tmp;

  PetscFunctionBeginUser;
  PetscCall(MatCreateVecs(ops->HfT, NULL, &ops->vd));
  PetscCall(VecDuplicate(ops->vd, &ops->vminus));
  PetscCall(VecDuplicate(ops->vd, &ops->r));
  PetscCall(VecDuplicate(ops->vd, &ops->v));
  PetscCall(MatMult(ops->HfT, ops->Vf, ops->vminus));
  if (ops->HgT) PetscCall(MatMultAdd(ops->HgT, ops->Vg, ops->vminus, ops->vminus));
  PetscCall(VecDuplicate(ops->Vf, &tmp));
  PetscCall(VecPointwiseMult(tmp, ops->Minv, ops->Rd));
  PetscCall(MatMult(ops->HfT, tmp, ops->vd));
  PetscCall(VecAXPY(ops->vd, 1.0, ops->vminus));
  PetscCall(VecDestroy(&tmp));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsAssemble(KergsOperators ops, KergsScene scene, KergsContacts contacts)
{
  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(KERGS_Assemble, 0, 0, 0, 0));
  PetscCall(DestroyStepObjects(ops));
  PetscCall(SetUpDofLayout(ops, scene));
  PetscCall(SetDofVectors(ops, scene));
  PetscCall(CreateHt(ops, scene, contacts, PETSC_TRUE, ops->nfree_local, ops->nfree, &ops->HfT));
  if (ops->ndrivenwalls) {
    PetscInt nglocal;
    PetscCall(VecGetLocalSize(ops->Vg, &nglocal));
    PetscCall(CreateHt(ops, scene, contacts, PETSC_FALSE, nglocal, ops->ngiven, &ops->HgT));
  }
  PetscCall(ComputeDelassus(ops, scene, contacts));
  PetscCall(ComputeFreeVelocity(ops));
  PetscCall(PetscLogEventEnd(KERGS_Assemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetHf(KergsOperators ops, Mat *Hf)
{
  PetscFunctionBeginUser;
  if (!ops->Hf) PetscCall(MatTranspose(ops->HfT, MAT_INITIAL_MATRIX, &ops->Hf));
  *Hf = ops->Hf;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetImpulses(KergsOperators ops, KergsContacts contacts)
{
  PetscScalar *r;

  PetscFunctionBeginUser;
  PetscCall(VecGetArray(ops->r, &r));
  for (PetscInt k = 0; k < contacts->n; k++)
    for (PetscInt c = 0; c < ops->ncomp; c++) r[k * ops->ncomp + c] = contacts->c[k].r[c];
  PetscCall(VecRestoreArray(ops->r, &r));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsSetImpulses(KergsOperators ops, KergsContacts contacts)
{
  const PetscScalar *r, *v;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(ops->r, &r));
  PetscCall(VecGetArrayRead(ops->v, &v));
  for (PetscInt k = 0; k < contacts->n; k++) {
    for (PetscInt c = 0; c < KERGS_MAXCOMP; c++) contacts->c[k].r[c] = contacts->c[k].v[c] = 0.0;
    for (PetscInt c = 0; c < ops->ncomp; c++) {
      contacts->c[k].r[c] = r[k * ops->ncomp + c];
      contacts->c[k].v[c] = v[k * ops->ncomp + c];
    }
  }
  PetscCall(VecRestoreArrayRead(ops->r, &r));
  PetscCall(VecRestoreArrayRead(ops->v, &v));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsUpdateVelocities(KergsOperators ops, KergsScene scene)
{
  const PetscScalar *vf;
  PetscInt           nd = ops->ndof_disk, lo;
  PetscMPIInt        size;

  PetscFunctionBeginUser;
  /* V_f^+ = V_f^- + M^-1 (H_f r + R^d) */
  PetscCall(MatMultTranspose(ops->HfT, ops->r, ops->R));
  PetscCall(VecAXPY(ops->R, 1.0, ops->Rd));
  PetscCall(VecPointwiseMult(ops->R, ops->R, ops->Minv));
  PetscCall(VecAXPY(ops->Vf, 1.0, ops->R));
  /* each rank's V_f holds its own disks' DOFs: copy them into the owned disks (ghosts follow in
     KergsSceneRefreshGhosts) */
  PetscCall(VecGetOwnershipRange(ops->Vf, &lo, NULL));
  PetscCall(VecGetArrayRead(ops->Vf, &vf));
  for (PetscInt i = 0; i < scene->nowned; i++) {
    for (PetscInt d = 0; d < KERGS_DIM; d++) scene->v[KERGS_DIM * i + d] = vf[i * nd + d];
    for (PetscInt d = KERGS_DIM; d < nd; d++) scene->omega[KERGS_NROT * i + d - KERGS_DIM] = vf[i * nd + d];
  }
  /* free walls live on the last rank: every rank gets their velocities (KERGS_DIM values per wall) */
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  for (PetscInt w = 0; w < scene->nwalls; w++) {
    PetscInt k = ops->wall_dof[w] - lo;
    if (scene->walls[w].kind != KERGS_WALL_FREE) continue;
    if (k >= 0 && k < ops->nfree_local)
      for (PetscInt d = 0; d < KERGS_DIM; d++) scene->walls[w].v[d] = vf[k + d];
    PetscCallMPI(MPI_Bcast(scene->walls[w].v, KERGS_DIM, MPIU_REAL, size - 1, ops->comm));
  }
  PetscCall(VecRestoreArrayRead(ops->Vf, &vf));
  PetscFunctionReturn(0);
}
