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
  PetscCall(VecDestroy(&ops->Vg));
  PetscCall(VecCreateMPI(ops->comm, nfree_local, ops->nfree, &ops->Vf));
  PetscCall(VecDuplicate(ops->Vf, &ops->Minv));
  PetscCall(VecDuplicate(ops->Vf, &ops->Rd));
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

/* ------------------------------------------------------------------------------------------------ */
/* W = H_f^T M^-1 H_f, assembled body by body                                                       */
/*
   M is block diagonal by bodies, so W = sum over free bodies q of H_q^T M_q^-1 H_q: body q couples every pair of
   contacts (alpha, beta) that touch it, by the block H_alpha,q M_q^-1 H_beta,q^T (ncomp x ncomp; H_alpha,q are the
   rows of contact alpha on q's DOFs). Each rank adds the terms of the disks it owns: their contacts are its own
   plus its foreign ones (detect.h), all known here with their global indices; rows of foreign contacts go to their
   owners through PETSc's stash. A free wall's terms are added by each rank for its own contacts at that wall, from
   the list of every contact at the wall (gathered: a free wall couples all of them). The pattern is counted
   exactly beforehand: row alpha holds the contacts at its body a (always owned by alpha's owner) and at its body
   b, alpha itself in both; for a ghost b the counts come from b's owner. W is symmetric: only its upper block
   triangle is stored (SBAIJ, blocks W_alpha,beta with beta >= alpha, diagonal blocks whole), by ncomp x ncomp
   blocks, one block row per contact (block size 1 when frictionless), as the sweep reads it. Only those blocks are
   computed and counted. Nothing of the size of W or H_f is built on the side.
*/

/* A contact at one body: global index, owning rank, whether it is coupled to the others (active, or W over all
   pairs), and its rows of H_f^T on the body's DOFs (h[c * nd + j]). */
typedef struct {
  PetscInt    index;
  PetscMPIInt owner;
  PetscBool   coupled;
  PetscReal   h[KERGS_MAXCOMP * (KERGS_DIM + KERGS_NROT)];
} BodyContact;

/* Whether W stores the block W_alpha,beta: the own block always; another only between coupled contacts. */
static inline PetscBool StoredBlock(const BodyContact *alpha, const BodyContact *beta)
{
  return (PetscBool)(alpha->index == beta->index || (alpha->coupled && beta->coupled));
}

/* The rows of contact ct restricted to the DOFs [dof, dof + nd) of one of its bodies. */
static void RestrictToBody(KergsOperators ops, KergsScene scene, const KergsContact *ct, PetscInt dof, PetscInt nd, PetscReal *h)
{
  HtRow fr, gr;

  for (PetscInt i = 0; i < ops->ncomp * nd; i++) h[i] = 0.0;
  for (PetscInt c = 0; c < ops->ncomp; c++) {
    ContactRows(ops, scene, ct, c, &fr, &gr);
    for (PetscInt j = 0; j < fr.ncol; j++)
      if (fr.col[j] >= dof && fr.col[j] < dof + nd) h[c * nd + fr.col[j] - dof] = fr.val[j];
  }
}

/* The contacts at each owned disk, in CSR form (start[q] .. start[q+1] in list): entry k < n is owned contact k,
   entry n + f is foreign contact f. */
static PetscErrorCode DiskIncidence(KergsScene scene, KergsContacts ct, PetscInt **start, PetscInt **list)
{
  const PetscInt nq = scene->nowned;
  PetscInt      *fill;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(nq + 1, start));
  for (PetscInt k = 0; k < ct->n; k++) {
    (*start)[ct->c[k].a + 1]++;
    if (ct->c[k].kind == KERGS_CONTACT_DISK_DISK && ct->c[k].b < nq) (*start)[ct->c[k].b + 1]++;
  }
  for (PetscInt f = 0; f < ct->nforeign; f++) (*start)[ct->foreign[f].b + 1]++;
  for (PetscInt q = 0; q < nq; q++) (*start)[q + 1] += (*start)[q];
  PetscCall(PetscMalloc1((*start)[nq] + 1, list));
  PetscCall(PetscMalloc1(nq + 1, &fill));
  PetscCall(PetscArraycpy(fill, *start, nq));
  for (PetscInt k = 0; k < ct->n; k++) {
    (*list)[fill[ct->c[k].a]++] = k;
    if (ct->c[k].kind == KERGS_CONTACT_DISK_DISK && ct->c[k].b < nq) (*list)[fill[ct->c[k].b]++] = k;
  }
  for (PetscInt f = 0; f < ct->nforeign; f++) (*list)[fill[ct->foreign[f].b]++] = ct->n + f;
  PetscCall(PetscFree(fill));
  PetscFunctionReturn(0);
}

/* The contacts at owned disk q, into bc[0 .. m): index and owner, and with rows their rows on q's DOFs (the pattern
   counts need no rows). */
static PetscInt DiskContacts(KergsOperators ops, KergsScene scene, KergsContacts ct, const PetscInt *start, const PetscInt *list, PetscInt q,
                             PetscBool rows, BodyContact *bc)
{
  const PetscInt nd = ops->ndof_disk, dof = KergsOperatorsDiskDof(ops, scene->gidx[q]);
  PetscMPIInt    rank;
  PetscInt       m = 0;

  (void)MPI_Comm_rank(ops->comm, &rank);
  for (PetscInt j = start[q]; j < start[q + 1]; j++, m++) {
    const PetscInt      e  = list[j];
    const KergsContact *c  = e < ct->n ? &ct->c[e] : &ct->foreign[e - ct->n];
    bc[m].index            = e < ct->n ? ct->start + e : ct->foreign_index[e - ct->n];
    bc[m].owner            = e < ct->n ? rank : (PetscMPIInt)scene->ghost_owner[c->a - scene->nowned];
    bc[m].coupled          = ops->W_active_only ? KergsContactIsActive(scene, c) : PETSC_TRUE;
    if (rows) RestrictToBody(ops, scene, c, dof, nd, bc[m].h);
  }
  return m;
}

/* Every contact at free wall w, on every rank (rows on the wall's KERGS_DIM DOFs); *m of them in *bc (PetscFree). */
static PetscErrorCode WallContacts(KergsOperators ops, KergsScene scene, KergsContacts ct, PetscInt w, PetscInt *m, BodyContact **bc)
{
  PetscMPIInt  size, rank, nmine = 0, *counts, *displs;
  BodyContact *mine;
  PetscInt     total = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  PetscCallMPI(MPI_Comm_rank(ops->comm, &rank));
  for (PetscInt k = 0; k < ct->n; k++) nmine += ct->c[k].kind == KERGS_CONTACT_DISK_WALL && ct->c[k].b == w;
  PetscCall(PetscMalloc1(nmine + 1, &mine));
  for (PetscInt k = 0, i = 0; k < ct->n; k++)
    if (ct->c[k].kind == KERGS_CONTACT_DISK_WALL && ct->c[k].b == w) {
      mine[i].index = ct->start + k;
      mine[i].owner = rank;
      mine[i].coupled = ops->W_active_only ? KergsContactIsActive(scene, &ct->c[k]) : PETSC_TRUE;
      RestrictToBody(ops, scene, &ct->c[k], ops->wall_dof[w], KERGS_DIM, mine[i++].h);
    }
  PetscCall(PetscMalloc2(size, &counts, size, &displs));
  nmine *= (PetscMPIInt)sizeof(BodyContact);
  PetscCallMPI(MPI_Allgather(&nmine, 1, MPI_INT, counts, 1, MPI_INT, ops->comm));
  for (PetscMPIInt p = 0; p < size; p++) {
    displs[p] = (PetscMPIInt)(total * (PetscInt)sizeof(BodyContact));
    total += counts[p] / (PetscMPIInt)sizeof(BodyContact);
  }
  PetscCall(PetscMalloc1(total + 1, bc));
  PetscCallMPI(MPI_Allgatherv(mine, nmine, MPI_BYTE, *bc, counts, displs, MPI_BYTE, ops->comm));
  *m = total;
  PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree(mine));
  PetscFunctionReturn(0);
}

/* Upper block pattern counts of row alpha (global contact index `row`) from the contacts bc[0 .. m) at one of its
   bodies: only the blocks W_alpha,beta with beta >= alpha are stored (and StoredBlock). Alpha is among them; when it
   is counted twice (dup) it is taken off once. The diagonal part holds those of rank `owner`. */
static void CountBlocks(const BodyContact *bc, PetscInt m, PetscInt row, PetscMPIInt owner, PetscBool dup, PetscInt *d, PetscInt *o)
{
  const BodyContact *alpha = NULL;

  for (PetscInt j = 0; j < m && !alpha; j++)
    if (bc[j].index == row) alpha = &bc[j];
  for (PetscInt j = 0; j < m; j++) {
    if (bc[j].index < row || !StoredBlock(alpha, &bc[j])) continue;
    if (bc[j].owner == owner) (*d)++;
    else (*o)++;
  }
  if (dup) (*d)--;
}

/* The counts of the rows of foreign contacts at owned disks, sent to their owners, added to dnz/onz there. */
static PetscErrorCode CountRemoteRows(KergsOperators ops, KergsScene scene, KergsContacts ct, const PetscInt *start, const PetscInt *list,
                                      BodyContact *bc, PetscInt *dnz, PetscInt *onz)
{
  PetscMPIInt size, *scount, *fill;
  PetscInt   *send, *recv, nrecv;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  if (size == 1) PetscFunctionReturn(0);
  PetscCall(PetscCalloc2(size, &scount, size, &fill));
  PetscCall(PetscMalloc1(3 * ct->nforeign + 1, &send));
  for (PetscInt f = 0; f < ct->nforeign; f++) scount[scene->ghost_owner[ct->foreign[f].a - scene->nowned]]++;
  for (PetscMPIInt p = 1; p < size; p++) fill[p] = fill[p - 1] + scount[p - 1];
  for (PetscInt q = 0; q < scene->nowned; q++) {
    PetscInt m = -1;
    for (PetscInt j = start[q]; j < start[q + 1]; j++) {
      PetscInt    f = list[j] - ct->n, d = 0, o = 0, *r;
      PetscMPIInt p;
      if (f < 0) continue;
      if (m < 0) m = DiskContacts(ops, scene, ct, start, list, q, PETSC_FALSE, bc);
      p = (PetscMPIInt)scene->ghost_owner[ct->foreign[f].a - scene->nowned];
      CountBlocks(bc, m, ct->foreign_index[f], p, PETSC_TRUE, &d, &o);
      r    = &send[3 * fill[p]++]; /* one record per foreign row: its index, then its counts */
      r[0] = ct->foreign_index[f];
      r[1] = d;
      r[2] = o;
    }
  }
  PetscCall(KergsExchangeRecords(ops->comm, 3 * sizeof(PetscInt), scount, send, NULL, &recv, &nrecv));
  nrecv *= 3;
  for (PetscInt i = 0; i < nrecv; i += 3) {
    const PetscInt k = recv[i] - ct->start;
    PetscCheck(k >= 0 && k < ct->n, PETSC_COMM_SELF, PETSC_ERR_PLIB, "W pattern: contact %" PetscInt_FMT " is not owned here", recv[i]);
    dnz[k] += recv[i + 1];
    onz[k] += recv[i + 2];
  }
  PetscCall(PetscFree(recv));
  PetscCall(PetscFree(send));
  PetscCall(PetscFree2(scount, fill));
  PetscFunctionReturn(0);
}

/* Add the blocks H_alpha,q M_q^-1 H_beta,q^T of body q (contacts bc[0 .. m), inverse masses minv on its nd DOFs)
   to the block rows of the contacts bc[rows[i]] (all of them when rows is NULL); only the upper blocks, beta >= alpha
   (global contact indices), as W is stored by its upper block triangle (W_beta,alpha = W_alpha,beta^T). */
static PetscErrorCode AddBodyBlocks(Mat W, PetscInt nc, PetscInt nd, const PetscReal *minv, const BodyContact *bc, PetscInt m, const PetscInt *rows,
                                    PetscInt nrows, PetscInt *cols, PetscScalar *vals)
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < (rows ? nrows : m); i++) {
    const BodyContact *a = &bc[rows ? rows[i] : i];
    PetscInt           n = 0;
    for (PetscInt j = 0; j < m; j++)
      if (bc[j].index >= a->index && StoredBlock(a, &bc[j])) cols[n++] = j;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt c = 0; c < nc; c++)
        for (PetscInt e = 0; e < nc; e++) {
          const BodyContact *b = &bc[cols[k]];
          PetscReal          w = 0.0;
          for (PetscInt d = 0; d < nd; d++) w += a->h[c * nd + d] * minv[d] * b->h[e * nd + d];
          vals[c * n * nc + k * nc + e] = w; /* row-major block row, as MatSetValuesBlocked takes it */
        }
    for (PetscInt k = 0; k < n; k++) cols[k] = bc[cols[k]].index;
    PetscCall(MatSetValuesBlocked(W, 1, &a->index, n, cols, vals, ADD_VALUES));
  }
  PetscFunctionReturn(0);
}

/* The free walls' terms: each rank adds the rows of its own contacts at each free wall; with the counts of those
   rows when dnz is given (then nothing is added). */
static PetscErrorCode AddWallTerms(KergsOperators ops, KergsScene scene, KergsContacts ct, PetscInt *dnz, PetscInt *onz)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(ops->comm, &rank));
  for (PetscInt w = 0; w < scene->nwalls; w++) {
    BodyContact *bc;
    PetscInt     m, *rows, nrows = 0, *cols;
    PetscScalar *vals;
    PetscReal    minv[KERGS_DIM];

    if (scene->walls[w].kind != KERGS_WALL_FREE) continue;
    PetscCall(WallContacts(ops, scene, ct, w, &m, &bc));
    PetscCall(PetscMalloc3(m + 1, &rows, m + 1, &cols, m * ops->ncomp * ops->ncomp + 1, &vals));
    for (PetscInt j = 0; j < m; j++)
      if (bc[j].owner == rank) rows[nrows++] = j;
    for (PetscInt d = 0; d < KERGS_DIM; d++) minv[d] = 1.0 / scene->walls[w].mass;
    if (dnz)
      for (PetscInt i = 0; i < nrows; i++) CountBlocks(bc, m, bc[rows[i]].index, rank, PETSC_TRUE, &dnz[bc[rows[i]].index - ct->start], &onz[bc[rows[i]].index - ct->start]);
    else PetscCall(AddBodyBlocks(ops->W, ops->ncomp, KERGS_DIM, minv, bc, m, rows, nrows, cols, vals));
    PetscCall(PetscFree3(rows, cols, vals));
    PetscCall(PetscFree(bc));
  }
  PetscFunctionReturn(0);
}

/* Exact block counts of this rank's rows: the contacts at body a (owned here), plus those at body b (owned here,
   from b's owner for a ghost, or at a free wall), alpha itself once. */
static PetscErrorCode CountPattern(KergsOperators ops, KergsScene scene, KergsContacts ct, const PetscInt *start, const PetscInt *list,
                                   BodyContact *bc, PetscInt *dnz, PetscInt *onz)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(ops->comm, &rank));
  for (PetscInt k = 0; k < ct->n; k++) dnz[k] = onz[k] = 0;
  for (PetscInt q = 0; q < scene->nowned; q++) {
    PetscInt m = -1;
    for (PetscInt j = start[q]; j < start[q + 1]; j++) {
      const PetscInt k = list[j];
      if (k >= ct->n) continue; /* a foreign row: counted by its owner, from CountRemoteRows */
      if (m < 0) m = DiskContacts(ops, scene, ct, start, list, q, PETSC_FALSE, bc);
      CountBlocks(bc, m, ct->start + k, rank, (PetscBool)(q != ct->c[k].a), &dnz[k], &onz[k]); /* at b: alpha is counted already */
    }
  }
  PetscCall(CountRemoteRows(ops, scene, ct, start, list, bc, dnz, onz));
  PetscCall(AddWallTerms(ops, scene, ct, dnz, onz));
  PetscFunctionReturn(0);
}

static PetscErrorCode ComputeDelassus(KergsOperators ops, KergsScene scene, KergsContacts ct)
{
  const PetscInt     nc = ops->ncomp, nd = ops->ndof_disk;
  PetscInt          *start, *list, *dnz, *onz, *cols, maxm = 1;
  BodyContact       *bc;
  PetscScalar       *vals;
  const PetscScalar *minv;

  PetscFunctionBeginUser;
  PetscCall(DiskIncidence(scene, ct, &start, &list));
  for (PetscInt q = 0; q < scene->nowned; q++) maxm = PetscMax(maxm, start[q + 1] - start[q]);
  PetscCall(PetscMalloc5(maxm, &bc, maxm, &cols, maxm * nc * nc, &vals, ct->n + 1, &dnz, ct->n + 1, &onz));
  PetscCall(CountPattern(ops, scene, ct, start, list, bc, dnz, onz));
  PetscCall(MatCreate(ops->comm, &ops->W));
  PetscCall(MatSetSizes(ops->W, ct->n * nc, ct->n * nc, PETSC_DETERMINE, PETSC_DETERMINE));
  PetscCall(MatSetBlockSize(ops->W, nc));
  PetscCall(MatSetType(ops->W, MATSBAIJ));
  PetscCall(MatSeqSBAIJSetPreallocation(ops->W, nc, 0, dnz));
  PetscCall(MatMPISBAIJSetPreallocation(ops->W, nc, 0, dnz, 0, onz));
  PetscCall(MatSetOption(ops->W, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(VecGetArrayRead(ops->Minv, &minv));
  for (PetscInt q = 0; q < scene->nowned; q++) {
    const PetscInt m = DiskContacts(ops, scene, ct, start, list, q, PETSC_TRUE, bc);
    PetscCall(AddBodyBlocks(ops->W, nc, nd, &minv[q * nd], bc, m, NULL, m, cols, vals));
  }
  PetscCall(VecRestoreArrayRead(ops->Minv, &minv));
  PetscCall(AddWallTerms(ops, scene, ct, NULL, NULL));
  PetscCall(MatAssemblyBegin(ops->W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ops->W, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree5(bc, cols, vals, dnz, onz));
  PetscCall(PetscFree(start));
  PetscCall(PetscFree(list));
  PetscFunctionReturn(0);
}

/* H_g^T: the given part of each contact's rows (NULL without driven walls). */
static PetscErrorCode BuildHg(KergsOperators ops, KergsScene scene, KergsContacts contacts)
{
  PetscInt nglocal;

  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&ops->HgT));
  if (!ops->ndrivenwalls) PetscFunctionReturn(0);
  PetscCall(VecGetLocalSize(ops->Vg, &nglocal));
  PetscCall(CreateHt(ops, scene, contacts, PETSC_FALSE, nglocal, ops->ngiven, &ops->HgT));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsBuildHf(KergsOperators ops, KergsScene scene, KergsContacts contacts)
{
  MatInfo info;

  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&ops->HfT));
  PetscCall(MatDestroy(&ops->Hf));
  PetscCall(CreateHt(ops, scene, contacts, PETSC_TRUE, ops->nfree_local, ops->nfree, &ops->HfT));
  PetscCall(MatGetInfo(ops->HfT, MAT_GLOBAL_SUM, &info));
  ops->nnz_Hf = info.nz_used;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsReleaseH(KergsOperators ops)
{
  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&ops->HfT));
  PetscCall(MatDestroy(&ops->Hf));
  PetscCall(MatDestroy(&ops->HgT));
  PetscFunctionReturn(0);
}

/* v^d = H_g^T V_g^+ + H_f^T (V_f^- + M^-1 R^d), with r and v of the same layout. H_g^T comes and, unless kept, goes
   before H_f^T is built, so that the two coexist only when kept. */
PetscErrorCode KergsOperatorsAssembleH(KergsOperators ops, KergsScene scene, KergsContacts contacts, PetscBool keep)
{
  Vec tmp;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(KERGS_Assemble, 0, 0, 0, 0));
  PetscCall(DestroyStepObjects(ops));
  PetscCall(SetUpDofLayout(ops, scene));
  PetscCall(SetDofVectors(ops, scene));
  PetscCall(VecCreateMPI(ops->comm, contacts->n * ops->ncomp, PETSC_DETERMINE, &ops->vd));
  PetscCall(VecDuplicate(ops->vd, &ops->r));
  PetscCall(VecDuplicate(ops->vd, &ops->v));
  PetscCall(BuildHg(ops, scene, contacts));
  if (ops->HgT) PetscCall(MatMult(ops->HgT, ops->Vg, ops->vd));
  else PetscCall(VecZeroEntries(ops->vd));
  if (!keep) PetscCall(MatDestroy(&ops->HgT));
  PetscCall(KergsOperatorsBuildHf(ops, scene, contacts));
  PetscCall(VecDuplicate(ops->Vf, &tmp));
  PetscCall(VecPointwiseMult(tmp, ops->Minv, ops->Rd));
  PetscCall(VecAXPY(tmp, 1.0, ops->Vf));
  PetscCall(MatMultAdd(ops->HfT, tmp, ops->vd, ops->vd));
  PetscCall(VecDestroy(&tmp));
  if (!keep) PetscCall(KergsOperatorsReleaseH(ops));
  PetscCall(PetscLogEventEnd(KERGS_Assemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* Scalar nonzeros of the whole W, as if stored in full: nz_used counts ncomp^2 per stored block, and an SBAIJ W
   stores the upper block triangle only, so that full = 2 stored - (diagonal blocks: ncomp^2 per contact). */
static PetscErrorCode FullNonzerosW(Mat W, PetscReal *nnz)
{
  MatInfo  info;
  PetscInt N, bs;

  PetscFunctionBeginUser;
  PetscCall(MatGetInfo(W, MAT_GLOBAL_SUM, &info));
  PetscCall(MatGetSize(W, &N, NULL));
  PetscCall(MatGetBlockSize(W, &bs));
  *nnz = 2.0 * info.nz_used - (PetscReal)N * bs;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsAssembleW(KergsOperators ops, KergsScene scene, KergsContacts contacts, PetscBool activeonly)
{
  PetscFunctionBeginUser;
  PetscCheck(ops->Minv && ops->vd, ops->comm, PETSC_ERR_ORDER, "KergsOperatorsAssembleW: call KergsOperatorsAssembleH first");
  PetscCall(PetscLogEventBegin(KERGS_Assemble, 0, 0, 0, 0));
  PetscCall(KergsOperatorsReleaseW(ops));
  ops->W_active_only = activeonly;
  PetscCall(ComputeDelassus(ops, scene, contacts));
  PetscCall(FullNonzerosW(ops->W, &ops->nnz_W));
  PetscCall(PetscLogEventEnd(KERGS_Assemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsReleaseW(KergsOperators ops)
{
  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&ops->W));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsAssemble(KergsOperators ops, KergsScene scene, KergsContacts contacts)
{
  PetscFunctionBeginUser;
  PetscCall(KergsOperatorsAssembleH(ops, scene, contacts, PETSC_TRUE));
  PetscCall(KergsOperatorsAssembleW(ops, scene, contacts, PETSC_FALSE));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetHf(KergsOperators ops, Mat *Hf)
{
  PetscFunctionBeginUser;
  if (!ops->Hf) PetscCall(MatTranspose(ops->HfT, MAT_INITIAL_MATRIX, &ops->Hf));
  *Hf = ops->Hf;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsGetFullW(KergsOperators ops, Mat *Wfull)
{
  PetscFunctionBeginUser;
  /* from SBAIJ, PETSc's conversion writes W_beta,alpha = W_alpha,beta^T below the diagonal */
  PetscCall(MatConvert(ops->W, ops->ncomp > 1 ? MATBAIJ : MATAIJ, MAT_INITIAL_MATRIX, Wfull));
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
  const PetscScalar *r;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(ops->r, &r));
  for (PetscInt k = 0; k < contacts->n; k++) {
    for (PetscInt c = 0; c < KERGS_MAXCOMP; c++) contacts->c[k].r[c] = 0.0;
    for (PetscInt c = 0; c < ops->ncomp; c++) contacts->c[k].r[c] = r[k * ops->ncomp + c];
  }
  PetscCall(VecRestoreArrayRead(ops->r, &r));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsUpdateVelocities(KergsOperators ops, KergsScene scene)
{
  const PetscScalar *vf;
  PetscInt           nd = ops->ndof_disk, lo;
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
