/* kergs detect: contact detection (docs/design.md: the "detect" step of Algorithm 1, parallel layout).

   Broad phase: a cell list over the bounding box of the disk centres, with cells at least as wide as the
   largest reach 2 max(R) + alert, so that every potential pair lies in the same or an adjacent cell.
   Narrow phase: disk-disk and disk-wall gaps, local frames (n from b towards a, t = (-n_y, n_x)).
   The search runs over this rank's owned disks and their ghosts (docs/design.md: parallel layout): O(local disks).
   Ownership: a disk-disk contact belongs to the owner of its disk of smaller grain id (body a), a disk-wall
   contact to the owner of the disk. The ghost layer is symmetric, so both ranks of a cut pair see it, and
   exactly one keeps it.
   Persistence: the key (a, kind, id of b) and impulse of every contact of the previous call are kept, and a new
   contact with the same key takes over the impulse r (warm start of Algorithm 1). Both lists are sorted by key,
   so one merge pass does it. */
#include <kergs/private/detectimpl.h>

/* Relative widening of the cells beyond the largest reach: keeps a pair at exactly the reach distance
   in adjacent cells in spite of the rounding of the cell index. */
#define KERGS_CELL_MARGIN 1e-8

/* What detection reads from the scene, fetched once per call through its accessors. */
typedef struct {
  KergsDisks       D;
  const char      *name;
  PetscReal        alert;
  PetscInt         nmaterials, nwalls;
  const PetscReal *mu; /* friction table, nmaterials x nmaterials */
  const KergsWall *walls;
} SceneData;

static PetscErrorCode GetSceneData(KergsScene scene, SceneData *sd)
{
  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(scene, &sd->D));
  PetscCall(KergsSceneGetName(scene, &sd->name));
  PetscCall(KergsSceneGetContactRule(scene, &sd->alert, NULL));
  PetscCall(KergsSceneGetMaterials(scene, &sd->nmaterials, &sd->mu));
  PetscCall(KergsSceneGetWalls(scene, &sd->nwalls, &sd->walls));
  PetscFunctionReturn(0);
}

/* A wall as the narrow phase needs it: origin a, unit direction e along a->b, outward unit normal n
   (left normal of a->b), length. */
typedef struct {
  PetscReal a[KERGS_DIM], e[KERGS_DIM], n[KERGS_DIM];
  PetscReal length;
  PetscBool infinite;
  PetscInt  material;
} WallFrame;

PetscErrorCode KergsContactsCreate(MPI_Comm comm, KergsContacts *contacts)
{
  KergsContacts ct;

  PetscFunctionBeginUser;
  PetscCheck(contacts, comm, PETSC_ERR_ARG_NULL, "KergsContactsCreate: output argument is NULL");
  PetscCall(KergsInitializePackage());
  PetscCall(PetscNew(&ct));
  ct->comm  = comm;
  *contacts = ct;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsContactsDestroy(KergsContacts *contacts)
{
  PetscFunctionBeginUser;
  if (!contacts || !*contacts) PetscFunctionReturn(0);
  PetscCall(PetscFree((*contacts)->c));
  PetscCall(PetscFree((*contacts)->prev));
  PetscCall(PetscFree((*contacts)->foreign));
  PetscCall(PetscFree((*contacts)->foreign_index));
  PetscCall(PetscFree((*contacts)->cellhead));
  PetscCall(PetscFree((*contacts)->next));
  PetscCall(PetscFree(*contacts));
  PetscFunctionReturn(0);
}

/* Make room for at least `needed` contacts in ct->c, growing geometrically. */
static PetscErrorCode ContactsReserve(KergsContacts ct, PetscInt needed)
{
  PetscInt nalloc;

  PetscFunctionBeginUser;
  if (needed <= ct->nalloc) PetscFunctionReturn(0);
  nalloc = PetscMax(PetscMax(2 * ct->nalloc, needed), 64);
  PetscCall(PetscRealloc((size_t)nalloc * sizeof(KergsContact), &ct->c));
  ct->nalloc = nalloc;
  PetscFunctionReturn(0);
}

/* The scene fields detection relies on, checked once per call (cheap next to the search). */
static PetscErrorCode CheckScene(KergsContacts ct, const SceneData *sd)
{
  PetscFunctionBeginUser;
  PetscCheck(sd->D.ndisks >= 0, ct->comm, PETSC_ERR_ARG_OUTOFRANGE, "Scene %s: negative number of disks %" PetscInt_FMT, sd->name,
             sd->D.ndisks);
  PetscCheck(0 <= sd->D.dstart && sd->D.dstart <= sd->D.dend && sd->D.dend <= sd->D.ndisks && sd->D.nowned == sd->D.dend - sd->D.dstart &&
                 sd->D.nlocal >= sd->D.nowned,
             PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "Scene %s: owned disk range [%" PetscInt_FMT ", %" PetscInt_FMT ") of %" PetscInt_FMT " disks does not match %" PetscInt_FMT
             " owned and %" PetscInt_FMT " local disks",
             sd->name, sd->D.dstart, sd->D.dend, sd->D.ndisks, sd->D.nowned, sd->D.nlocal);
  PetscCheck(sd->alert >= 0.0, ct->comm, PETSC_ERR_ARG_OUTOFRANGE, "Scene %s: alert distance %g must be >= 0", sd->name, (double)sd->alert);
  PetscCheck(sd->nmaterials > 0 && sd->mu, ct->comm, PETSC_ERR_ARG_WRONGSTATE, "Scene %s: no materials (friction table missing)", sd->name);
  PetscFunctionReturn(0);
}

/* Find the disk that made the bounding-box pass fail (non-finite centre, radius not positive and finite,
   material out of range) and report it by grain id. Only called on the error path. */
static PetscErrorCode ReportBadDisk(KergsContacts ct, const SceneData *sd)
{
  const PetscReal *x = sd->D.x, *rad = sd->D.radius;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < sd->D.nlocal; i++) {
    PetscCheck(!PetscIsInfOrNanReal(x[KERGS_DIM * i]) && !PetscIsInfOrNanReal(x[KERGS_DIM * i + 1]), ct->comm, PETSC_ERR_FP,
               "Scene %s: grain %" PetscInt_FMT " (disk %" PetscInt_FMT ") has a non-finite centre", sd->name, sd->D.id[i], sd->D.gidx[i]);
    PetscCheck(rad[i] > 0.0 && !PetscIsInfOrNanReal(rad[i]), ct->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Scene %s: grain %" PetscInt_FMT " (disk %" PetscInt_FMT ") has radius %g, not positive and finite", sd->name, sd->D.id[i],
               sd->D.gidx[i], (double)rad[i]);
    PetscCheck(0 <= sd->D.material[i] && sd->D.material[i] < sd->nmaterials, ct->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Scene %s: grain %" PetscInt_FMT " (disk %" PetscInt_FMT ") has material %" PetscInt_FMT ", outside [0, %" PetscInt_FMT ")",
               sd->name, sd->D.id[i], sd->D.gidx[i], sd->D.material[i], sd->nmaterials);
  }
  SETERRQ(ct->comm, PETSC_ERR_FP, "Scene %s: the bounding box of the disk centres is too large to represent", sd->name);
}

/* Bounding box of the centres and largest radius, in one pass over the disks that also checks radii and
   materials (so that the search loops can index the friction table without checks). */
static PetscErrorCode BoundingBox(KergsContacts ct, const SceneData *sd, PetscReal lo[], PetscReal hi[], PetscReal *rmax)
{
  const PetscReal *x = sd->D.x, *rad = sd->D.radius;
  const PetscInt  *mat  = sd->D.material;
  PetscReal        rmin = PETSC_MAX_REAL, rbig = 0.0;
  PetscInt         matmin = 0, matmax = 0;
  PetscBool        finite = PETSC_TRUE;

  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    lo[d] = PETSC_MAX_REAL;
    hi[d] = -PETSC_MAX_REAL;
  }
  for (PetscInt i = 0; i < sd->D.nlocal; i++) {
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      const PetscReal xi = x[KERGS_DIM * i + d];
      lo[d]              = PetscMin(lo[d], xi);
      hi[d]              = PetscMax(hi[d], xi);
    }
    rmin   = PetscMin(rmin, rad[i]);
    rbig   = PetscMax(rbig, rad[i]);
    matmin = PetscMin(matmin, mat[i]);
    matmax = PetscMax(matmax, mat[i]);
  }
  if (sd->D.nlocal == 0) {
    for (PetscInt d = 0; d < KERGS_DIM; d++) lo[d] = hi[d] = 0.0;
  }
  /* NaN fails every comparison: a NaN centre or radius makes the box or the radius bounds fail below */
  for (PetscInt d = 0; d < KERGS_DIM; d++) finite = (PetscBool)(finite && !PetscIsInfOrNanReal(hi[d] - lo[d]));
  if (sd->D.nlocal > 0 && (!finite || !(rmin > 0.0) || PetscIsInfOrNanReal(rbig) || matmin < 0 || matmax >= sd->nmaterials))
    PetscCall(ReportBadDisk(ct, sd));
  *rmax = rbig;
  PetscFunctionReturn(0);
}

/* Rebuild the cell list over the bounding box of the local (owned and ghost) centres. Cells are squares of side
   h >= 2 max(R) + alert (the largest possible reach of a pair), widened if needed so that the grid has
   at most 4 nlocal + 64 cells (one disk far away must not make a huge grid). */
static PetscErrorCode BuildCellList(KergsContacts ct, const SceneData *sd)
{
  const PetscInt   n        = sd->D.nlocal;
  const PetscReal *x        = sd->D.x;
  const PetscReal  maxcells = 4.0 * (PetscReal)n + 64.0;
  PetscReal        lo[KERGS_DIM], hi[KERGS_DIM], rmax = 0.0, h, inv, extent[KERGS_DIM];
  PetscInt         ncells;

  PetscFunctionBeginUser;
  PetscCall(BoundingBox(ct, sd, lo, hi, &rmax));
  for (PetscInt d = 0; d < KERGS_DIM; d++) extent[d] = hi[d] - lo[d];
  h = (2.0 * rmax + sd->alert) * (1.0 + KERGS_CELL_MARGIN);
  if (!(h > 0.0)) h = 1.0;
  if ((extent[0] / h + 1.0) * (extent[1] / h + 1.0) > maxcells) {
    h = PetscMax(h, PetscSqrtReal(extent[0] * extent[1] / maxcells));
    while ((extent[0] / h + 1.0) * (extent[1] / h + 1.0) > maxcells) h *= 1.1;
  }
  ct->cellsize  = h;
  ct->origin[0] = lo[0];
  ct->origin[1] = lo[1];
  ct->ncellx    = (PetscInt)(extent[0] / h) + 1;
  ct->ncelly    = (PetscInt)(extent[1] / h) + 1;
  ncells        = ct->ncellx * ct->ncelly;
  if (ncells > ct->ncellalloc) {
    ct->ncellalloc = PetscMax(ncells, 2 * ct->ncellalloc);
    PetscCall(PetscFree(ct->cellhead));
    PetscCall(PetscMalloc1(ct->ncellalloc, &ct->cellhead));
  }
  if (n > ct->nnextalloc) {
    ct->nnextalloc = PetscMax(n, 2 * ct->nnextalloc);
    PetscCall(PetscFree(ct->next));
    PetscCall(PetscMalloc1(ct->nnextalloc, &ct->next));
  }
  for (PetscInt c = 0; c < ncells; c++) ct->cellhead[c] = -1;
  /* push disks in increasing order: each cell's chain then runs in decreasing index order */
  inv = 1.0 / h;
  for (PetscInt i = 0; i < n; i++) {
    PetscInt ix = (PetscInt)((x[KERGS_DIM * i] - lo[0]) * inv), iy = (PetscInt)((x[KERGS_DIM * i + 1] - lo[1]) * inv), cell;

    ix                 = PetscMin(PetscMax(ix, 0), ct->ncellx - 1);
    iy                 = PetscMin(PetscMax(iy, 0), ct->ncelly - 1);
    cell               = iy * ct->ncellx + ix;
    ct->next[i]        = ct->cellhead[cell];
    ct->cellhead[cell] = i;
  }
  PetscFunctionReturn(0);
}

/* Fill a contact with its geometry; a fresh contact has no impulse, no velocity, and is not persistent
   until the merge with the previous detection says otherwise. */
static inline void SetContact(KergsContact *c, KergsContactKind kind, PetscInt a, PetscInt b, PetscInt idb, PetscReal nx, PetscReal ny,
                              PetscReal ra, PetscReal rb, PetscReal gap, PetscReal mu)
{
  c->kind = kind;
  c->a    = a;
  c->b    = b;
  c->idb  = idb;
  c->n[0] = nx;
  c->n[1] = ny;
  c->t[0] = -ny; /* t = (-n_y, n_x) */
  c->t[1] = nx;
  c->ra   = ra;
  c->rb   = rb;
  c->gap  = gap;
  c->mu   = mu;
  for (PetscInt k = 0; k < KERGS_MAXCOMP; k++) c->r[k] = 0.0;
  c->persistent = PETSC_FALSE;
}

/* The disk-disk pair (p, q), p of smaller grain id, as contact c if it lies within the alert distance (returns
   PETSC_FALSE otherwise). Gap g = |x_p - x_q| - R_p - R_q, normal n = (x_p - x_q) / |x_p - x_q|. Always evaluated
   in this order, so that the two ranks holding the pair (one of them as a ghost) compute the same bits. */
static PetscErrorCode PairContact(const SceneData *sd, PetscInt p, PetscInt q, KergsContact *c, PetscBool *touching)
{
  const PetscReal *x = sd->D.x, *rad = sd->D.radius;
  const PetscReal  dx = x[KERGS_DIM * p] - x[KERGS_DIM * q], dy = x[KERGS_DIM * p + 1] - x[KERGS_DIM * q + 1];
  const PetscReal  reach = rad[p] + rad[q] + sd->alert, d2 = dx * dx + dy * dy;
  PetscReal        dist;

  PetscFunctionBeginUser;
  *touching = (PetscBool)(d2 < reach * reach);
  if (!*touching) PetscFunctionReturn(0);
  PetscCheck(d2 > 0.0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "Scene %s: grains %" PetscInt_FMT " and %" PetscInt_FMT " (disks %" PetscInt_FMT " and %" PetscInt_FMT
             ") have coincident centres (%g, %g): contact normal undefined",
             sd->name, sd->D.id[p], sd->D.id[q], sd->D.gidx[p], sd->D.gidx[q], (double)x[KERGS_DIM * p], (double)x[KERGS_DIM * p + 1]);
  dist = PetscSqrtReal(d2);
  SetContact(c, KERGS_CONTACT_DISK_DISK, p, q, sd->D.id[q], dx / dist, dy / dist, rad[p], rad[q], dist - rad[p] - rad[q],
             sd->mu[sd->D.material[p] * sd->nmaterials + sd->D.material[q]]);
  PetscFunctionReturn(0);
}

static PetscErrorCode ForeignReserve(KergsContacts ct, PetscInt needed)
{
  PetscFunctionBeginUser;
  if (needed <= ct->nforeignalloc) PetscFunctionReturn(0);
  ct->nforeignalloc = PetscMax(PetscMax(2 * ct->nforeignalloc, needed), 16);
  PetscCall(PetscRealloc((size_t)ct->nforeignalloc * sizeof(KergsContact), &ct->foreign));
  PetscCall(PetscRealloc((size_t)ct->nforeignalloc * sizeof(PetscInt), &ct->foreign_index));
  PetscFunctionReturn(0);
}

/* Contacts of owned disk a with every local disk b of larger grain id within the alert distance, appended to
   ct->c and sorted by the id of b; and the foreign contacts of a: those with a ghost b of smaller id (owned by
   b's owner), appended to ct->foreign as the pair (b, a). */
static PetscErrorCode DetectDiskDisk(KergsContacts ct, const SceneData *sd, PetscInt a)
{
  const PetscReal *x    = sd->D.x;
  const PetscInt  *next = ct->next, *head = ct->cellhead, nx = ct->ncellx, ny = ct->ncelly;
  const PetscReal  xa = x[KERGS_DIM * a], ya = x[KERGS_DIM * a + 1], inv = 1.0 / ct->cellsize;
  const PetscInt   first = ct->n, *id = sd->D.id, ida = id[a];
  PetscInt         ix = (PetscInt)((xa - ct->origin[0]) * inv), iy = (PetscInt)((ya - ct->origin[1]) * inv);
  PetscBool        touching;

  PetscFunctionBeginUser;
  ix = PetscMin(PetscMax(ix, 0), nx - 1);
  iy = PetscMin(PetscMax(iy, 0), ny - 1);
  for (PetscInt cy = PetscMax(iy - 1, 0); cy <= PetscMin(iy + 1, ny - 1); cy++) {
    for (PetscInt cx = PetscMax(ix - 1, 0); cx <= PetscMin(ix + 1, nx - 1); cx++) {
      for (PetscInt b = head[cy * nx + cx]; b >= 0; b = next[b]) {
        if (id[b] > ida) { /* the pair belongs to the disk of smaller id: a */
          if (ct->n == ct->nalloc) PetscCall(ContactsReserve(ct, ct->n + 1));
          PetscCall(PairContact(sd, a, b, &ct->c[ct->n], &touching));
          ct->n += touching;
        } else if (b >= sd->D.nowned) { /* a ghost of smaller id: the pair is its owner's, foreign here */
          PetscCall(ForeignReserve(ct, ct->nforeign + 1));
          PetscCall(PairContact(sd, b, a, &ct->foreign[ct->nforeign], &touching));
          ct->nforeign += touching;
        } /* b == a, or an owned disk of smaller id: found from b */
      }
    }
  }
  /* the few contacts of disk a come from up to 9 cells: insertion sort by the id of b */
  for (PetscInt i = first + 1; i < ct->n; i++) {
    KergsContact key = ct->c[i];
    PetscInt     j   = i - 1;

    while (j >= first && ct->c[j].idb > key.idb) {
      ct->c[j + 1] = ct->c[j];
      j--;
    }
    ct->c[j + 1] = key;
  }
  PetscFunctionReturn(0);
}

/* Frames of the walls; a wall of zero length has no normal. */
static PetscErrorCode SetUpWallFrames(const SceneData *sd, WallFrame *frames)
{
  PetscFunctionBeginUser;
  for (PetscInt w = 0; w < sd->nwalls; w++) {
    const KergsWall *wall = &sd->walls[w];
    const PetscReal  ex = wall->b[0] - wall->a[0], ey = wall->b[1] - wall->a[1], len = PetscSqrtReal(ex * ex + ey * ey);

    PetscCheck(0 <= wall->material && wall->material < sd->nmaterials, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "Scene %s: wall %" PetscInt_FMT " (%s) has material %" PetscInt_FMT ", outside [0, %" PetscInt_FMT ")", sd->name, w,
               wall->name, wall->material, sd->nmaterials);
    PetscCheck(len > 0.0 && !PetscIsInfOrNanReal(len), PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "Scene %s: wall %" PetscInt_FMT " (%s) from (%g, %g) to (%g, %g) has no direction", sd->name, w, wall->name,
               (double)wall->a[0], (double)wall->a[1], (double)wall->b[0], (double)wall->b[1]);
    frames[w].a[0]     = wall->a[0];
    frames[w].a[1]     = wall->a[1];
    frames[w].e[0]     = ex / len;
    frames[w].e[1]     = ey / len;
    frames[w].n[0]     = -ey / len; /* left normal of a->b: the outward side */
    frames[w].n[1]     = ex / len;
    frames[w].length   = len;
    frames[w].infinite = wall->infinite;
    frames[w].material = wall->material;
  }
  PetscFunctionReturn(0);
}

/* Contacts of owned disk a with the walls, in wall order. The wall is one-sided: the centre must lie on
   the outward side (signed distance d = (x - a).n > 0) with gap d - R < alert, and for a segment its
   projection (x - a).e must fall on [0, |b - a|]. The normal is the wall's, from the wall to the disk. */
static PetscErrorCode DetectDiskWall(KergsContacts ct, const SceneData *sd, const WallFrame *frames, PetscInt a)
{
  const PetscReal xa = sd->D.x[KERGS_DIM * a], ya = sd->D.x[KERGS_DIM * a + 1], ra = sd->D.radius[a];

  PetscFunctionBeginUser;
  for (PetscInt w = 0; w < sd->nwalls; w++) {
    const WallFrame *f  = &frames[w];
    const PetscReal  dx = xa - f->a[0], dy = ya - f->a[1], d = dx * f->n[0] + dy * f->n[1];

    if (!(d > 0.0 && d - ra < sd->alert)) continue;
    if (!f->infinite) {
      const PetscReal s = dx * f->e[0] + dy * f->e[1];
      if (s < 0.0 || s > f->length) continue;
    }
    if (ct->n == ct->nalloc) PetscCall(ContactsReserve(ct, ct->n + 1));
    SetContact(&ct->c[ct->n++], KERGS_CONTACT_DISK_WALL, a, w, w, f->n[0], f->n[1], ra, 0.0, d - ra,
               sd->mu[sd->D.material[a] * sd->nmaterials + f->material]);
  }
  PetscFunctionReturn(0);
}

int KergsContactHistoryCompare(const void *p, const void *q)
{
  return KERGS_COMPARE_KEYS((const KergsContactHistory *)p, (const KergsContactHistory *)q);
}

/* Keep the key and impulse of every current contact for the next call's warm start (sorted by key). */
static PetscErrorCode SaveHistory(KergsContacts ct)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(ct->prev));
  PetscCall(PetscMalloc1(ct->n + 1, &ct->prev));
  ct->nprev = ct->n;
  for (PetscInt i = 0; i < ct->n; i++) {
    KergsContactHistory *h = &ct->prev[i];
    h->a                   = ct->c[i].a;
    h->idb                 = ct->c[i].idb;
    h->kind                = ct->c[i].kind;
    for (PetscInt k = 0; k < KERGS_MAXCOMP; k++) h->r[k] = ct->c[i].r[k];
  }
  /* the list is sorted unless a caller reordered it (the migration of contacts sorts what it receives) */
  for (PetscInt k = 1; k < ct->nprev; k++)
    if (KERGS_COMPARE_KEYS(&ct->prev[k - 1], &ct->prev[k]) > 0) {
      qsort(ct->prev, (size_t)ct->nprev, sizeof(KergsContactHistory), KergsContactHistoryCompare);
      break;
    }
  PetscFunctionReturn(0);
}

/* Warm start: a contact of the same (a, kind, idb) as one of the previous call takes over its impulse.
   Both lists are sorted, so one merge pass finds every match (O(n + nprev)). */
static PetscErrorCode CarryOverImpulses(KergsContacts ct)
{
  PetscInt j = 0;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < ct->n && j < ct->nprev; i++) {
    KergsContact *c = &ct->c[i];

    while (j < ct->nprev && KERGS_COMPARE_KEYS(&ct->prev[j], c) < 0) j++;
    if (j < ct->nprev && KERGS_COMPARE_KEYS(&ct->prev[j], c) == 0) {
      for (PetscInt k = 0; k < KERGS_MAXCOMP; k++) c->r[k] = ct->prev[j].r[k];
      c->persistent = PETSC_TRUE;
    }
  }
  PetscFunctionReturn(0);
}

/* Global numbering of the contacts: rank p's contacts come after those of ranks 0 .. p-1 (collective). */
static PetscErrorCode SetGlobalNumbering(KergsContacts ct)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(ct->comm, &rank));
  PetscCallMPI(MPI_Allreduce(&ct->n, &ct->nglobal, 1, MPIU_INT, MPI_SUM, ct->comm));
  ct->start = 0;
  PetscCallMPI(MPI_Exscan(&ct->n, &ct->start, 1, MPIU_INT, MPI_SUM, ct->comm));
  if (rank == 0) ct->start = 0; /* MPI_Exscan leaves rank 0's result undefined */
  PetscFunctionReturn(0);
}

/* A key of a disk-disk contact by grain ids and its global index, as owners send it to the ranks holding it as
   foreign. */
typedef struct {
  PetscInt ida, idb, index;
} ForeignKey;

static int CompareForeignKeys(const void *x, const void *y)
{
  const ForeignKey *p = (const ForeignKey *)x, *q = (const ForeignKey *)y;
  if (p->ida != q->ida) return p->ida < q->ida ? -1 : 1;
  return p->idb < q->idb ? -1 : (p->idb > q->idb ? 1 : 0);
}

/* The global index of every foreign contact, from its owner: each rank sends (ids, index) of its contacts with a
   ghost b to b's owner (one personalised exchange), which matches them with its foreign list. Both sides found the
   pair from the same bits, so the lists must agree exactly; a mismatch is an error, not a silent loss. */
static PetscErrorCode NumberForeignContacts(KergsContacts ct, const SceneData *sd)
{
  PetscMPIInt size, *scount, *fill;
  ForeignKey *send, *recv, *mine;
  PetscInt    nsend = 0, nrecv;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(ct->comm, &size));
  if (size == 1) PetscFunctionReturn(0);
  PetscCall(PetscCalloc2(size, &scount, size, &fill));
  for (PetscInt k = 0; k < ct->n; k++)
    if (ct->c[k].kind == KERGS_CONTACT_DISK_DISK && ct->c[k].b >= sd->D.nowned) {
      scount[sd->D.ghost_owner[ct->c[k].b - sd->D.nowned]]++;
      nsend++;
    }
  PetscCall(PetscMalloc1(nsend + 1, &send));
  for (PetscMPIInt q = 1; q < size; q++) fill[q] = fill[q - 1] + scount[q - 1];
  for (PetscInt k = 0; k < ct->n; k++) {
    const KergsContact *c = &ct->c[k];
    if (c->kind != KERGS_CONTACT_DISK_DISK || c->b < sd->D.nowned) continue;
    send[fill[sd->D.ghost_owner[c->b - sd->D.nowned]]++] = (ForeignKey){sd->D.id[c->a], c->idb, ct->start + k};
  }
  PetscCall(KergsExchangeRecords(ct->comm, sizeof(ForeignKey), scount, send, NULL, &recv, &nrecv));
  PetscCall(PetscMalloc1(ct->nforeign + 1, &mine));
  PetscCheck(nrecv == ct->nforeign, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "Scene %s: %" PetscInt_FMT " contacts of other ranks touch this rank's disks, but %" PetscInt_FMT
             " were found here (ghost layer incomplete)",
             sd->name, nrecv, ct->nforeign);
  for (PetscInt f = 0; f < ct->nforeign; f++) mine[f] = (ForeignKey){sd->D.id[ct->foreign[f].a], ct->foreign[f].idb, f};
  qsort(recv, (size_t)nrecv, sizeof(ForeignKey), CompareForeignKeys);
  qsort(mine, (size_t)ct->nforeign, sizeof(ForeignKey), CompareForeignKeys);
  for (PetscInt f = 0; f < ct->nforeign; f++) {
    PetscCheck(CompareForeignKeys(&recv[f], &mine[f]) == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "Scene %s: the pair of grains %" PetscInt_FMT " and %" PetscInt_FMT " is a contact on one rank and not on the other",
               sd->name, recv[f].ida, recv[f].idb);
    ct->foreign_index[mine[f].index] = recv[f].index;
  }
  PetscCall(PetscFree(recv));
  PetscCall(PetscFree(mine));
  PetscCall(PetscFree(send));
  PetscCall(PetscFree2(scount, fill));
  PetscFunctionReturn(0);
}

static PetscErrorCode DetectContacts(KergsContacts ct, KergsScene scene)
{
  WallFrame *frames      = NULL;
  PetscInt   npersistent = 0;
  SceneData  scenedata, *sd = &scenedata;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneUpdateGhosts(scene, PETSC_FALSE)); /* a ghost layer exists and is fresh enough for this search */
  PetscCall(GetSceneData(scene, sd));
  PetscCall(CheckScene(ct, sd));
  /* the current contacts leave their keys and impulses; their storage is reused for the new list */
  PetscCall(SaveHistory(ct));
  ct->n = ct->nforeign = 0;

  PetscCall(BuildCellList(ct, sd));
  PetscCall(PetscMalloc1(sd->nwalls, &frames));
  PetscCall(SetUpWallFrames(sd, frames));
  for (PetscInt a = 0; a < sd->D.nowned; a++) {
    PetscCall(DetectDiskDisk(ct, sd, a));
    PetscCall(DetectDiskWall(ct, sd, frames, a));
  }
  PetscCall(PetscFree(frames));
  PetscCall(CarryOverImpulses(ct));
  /* the history served its purpose: freed, so that it does not add to the step's peak memory (the solve) */
  PetscCall(PetscFree(ct->prev));
  ct->nprev = 0;
  PetscCall(SetGlobalNumbering(ct));
  PetscCall(NumberForeignContacts(ct, sd));
  for (PetscInt i = 0; i < ct->n; i++) npersistent += ct->c[i].persistent;
  PetscCall(PetscInfo(NULL,
                      "Scene %s: %" PetscInt_FMT " contacts here (%" PetscInt_FMT " persistent) of %" PetscInt_FMT
                      ", cell grid %" PetscInt_FMT " x %" PetscInt_FMT " of side %g\n",
                      sd->name, ct->n, npersistent, ct->nglobal, ct->ncellx, ct->ncelly, (double)ct->cellsize));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsContactsDetect(KergsContacts ct, KergsScene scene)
{
  PetscErrorCode ierr;

  PetscFunctionBeginUser;
  PetscCheck(ct && scene, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KergsContactsDetect: contacts or scene is NULL");
  /* end the log event even on error, so that a caller that recovers still gets a readable -log_view */
  PetscCall(PetscLogEventBegin(KERGS_Detect, 0, 0, 0, 0));
  ierr = DetectContacts(ct, scene);
  PetscCall(PetscLogEventEnd(KERGS_Detect, 0, 0, 0, 0));
  PetscCall(ierr);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsContactsGetActivity(KergsContacts ct, KergsScene scene, KergsActivity *act)
{
  KergsDisks D;
  PetscReal  dt, theta;

  PetscFunctionBeginUser;
  (void)ct;
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetContactRule(scene, NULL, &act->rule));
  PetscCall(KergsSceneGetTimeStep(scene, &dt, &theta));
  PetscCall(KergsSceneGetWalls(scene, NULL, &act->walls));
  act->lead     = (1.0 - theta) * dt;
  act->theta_dt = theta * dt;
  act->v        = D.v;
  PetscFunctionReturn(0);
}

/* g~ = g^- + (1 - theta) dt v_n^-, v_n^- = n.(V_a - V_b) (the normal row of H^T has no rotation term) */
static PetscReal PredictedGap(const KergsActivity *act, const KergsContact *c)
{
  const PetscReal *va = &act->v[KERGS_DIM * c->a];
  const PetscReal *vb = c->kind == KERGS_CONTACT_DISK_DISK ? &act->v[KERGS_DIM * c->b] : act->walls[c->b].v;
  PetscReal        vn = 0.0;

  if (act->lead == 0.0) return c->gap;
  for (PetscInt d = 0; d < KERGS_DIM; d++) vn += c->n[d] * (va[d] - vb[d]);
  return c->gap + act->lead * vn;
}

PetscBool KergsContactIsActive(const KergsActivity *act, const KergsContact *c)
{
  switch (act->rule) {
  case KERGS_GAP_PREDICTIVE:
    return PETSC_TRUE; /* every detected contact: closer than the alert distance */
  case KERGS_GAP_LMGC90:
    return (PetscBool)(PredictedGap(act, c) <= 0.0);
  default:
    return (PetscBool)(c->gap <= 0.0);
  }
}

PetscReal KergsContactGapVelocity(const KergsActivity *act, const KergsContact *c)
{
  if (act->rule != KERGS_GAP_PREDICTIVE || !(act->theta_dt > 0)) return 0.0;
  return PetscMax(PredictedGap(act, c), 0.0) / act->theta_dt;
}

PetscErrorCode KergsContactsGetLocal(KergsContacts ct, PetscInt *n, KergsContact **c)
{
  PetscFunctionBeginUser;
  if (n) *n = ct->n;
  if (c) *c = ct->c;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsContactsGetForeign(KergsContacts ct, PetscInt *n, const KergsContact **c, const PetscInt **index)
{
  PetscFunctionBeginUser;
  if (n) *n = ct->nforeign;
  if (c) *c = ct->foreign;
  if (index) *index = ct->foreign_index;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsContactsGetGlobalRange(KergsContacts ct, PetscInt *start, PetscInt *nglobal)
{
  PetscFunctionBeginUser;
  if (start) *start = ct->start;
  if (nglobal) *nglobal = ct->nglobal;
  PetscFunctionReturn(0);
}

/* Send every contact to the new owner of its disk a. The received ones replace ct->c, sorted by key and holding
   only their key and impulse (b = -1: the ghost layer is gone), so that the next detection carries the impulses
   over; nothing else may read them before that detection. A contact travels as its history record (detect.h), a
   being its new global index; its frame needs no change: body a is the disk of smaller grain id whatever the
   numbering. */
PetscErrorCode KergsContactsMigrate(KergsContacts ct, const PetscInt newidx[], const PetscInt newranges[])
{
  PetscMPIInt          rank, size, *scount, *fill, *dest;
  KergsContactHistory *sendbuf, *recvbuf;
  PetscInt             nrecv;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(ct->comm, &rank));
  PetscCallMPI(MPI_Comm_size(ct->comm, &size));
  PetscCall(PetscCalloc2(size, &scount, size, &fill));
  PetscCall(PetscMalloc2(ct->n + 1, &dest, ct->n + 1, &sendbuf));
  for (PetscInt k = 0; k < ct->n; k++) {
    dest[k] = KergsRangeOwner(newranges, size, newidx[ct->c[k].a]);
    scount[dest[k]]++;
  }
  for (PetscMPIInt q = 1; q < size; q++) fill[q] = fill[q - 1] + scount[q - 1];
  for (PetscInt k = 0; k < ct->n; k++) {
    KergsContactHistory *m = &sendbuf[fill[dest[k]]++];
    m->a                   = newidx[ct->c[k].a];
    m->idb                 = ct->c[k].idb;
    m->kind                = ct->c[k].kind;
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) m->r[j] = ct->c[k].r[j];
  }
  PetscCall(KergsExchangeRecords(ct->comm, sizeof(KergsContactHistory), scount, sendbuf, NULL, &recvbuf, &nrecv));
  qsort(recvbuf, (size_t)nrecv, sizeof(KergsContactHistory), KergsContactHistoryCompare); /* new indices: same order as local ones */
  if (nrecv > ct->nalloc) {
    PetscCall(PetscFree(ct->c));
    PetscCall(PetscMalloc1(nrecv, &ct->c));
    ct->nalloc = nrecv;
  }
  for (PetscInt k = 0; k < nrecv; k++) {
    KergsContact *c = &ct->c[k];
    PetscCall(PetscMemzero(c, sizeof(*c)));
    c->a    = recvbuf[k].a - newranges[rank];
    c->b    = -1;
    c->idb  = recvbuf[k].idb;
    c->kind = recvbuf[k].kind;
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) c->r[j] = recvbuf[k].r[j];
  }
  ct->n     = nrecv;
  ct->start = 0;
  PetscCallMPI(MPI_Exscan(&ct->n, &ct->start, 1, MPIU_INT, MPI_SUM, ct->comm));
  if (rank == 0) ct->start = 0; /* MPI_Exscan leaves rank 0's result undefined */
  PetscCall(PetscFree(recvbuf));
  PetscCall(PetscFree2(scount, fill));
  PetscCall(PetscFree2(dest, sendbuf));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsContactsRestore(KergsContacts ct, PetscInt n, const KergsContact c[])
{
  PetscFunctionBeginUser;
  for (PetscInt k = 1; k < n; k++)
    PetscCheck(KERGS_COMPARE_KEYS(&c[k - 1], &c[k]) < 0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "Restored contacts %" PetscInt_FMT " and %" PetscInt_FMT " are not in the order of their keys (a, kind, id of b)", k - 1, k);
  PetscCall(ContactsReserve(ct, n));
  if (n) PetscCall(PetscArraycpy(ct->c, c, n));
  ct->n        = n;
  ct->nforeign = 0;
  PetscCall(SetGlobalNumbering(ct));
  PetscFunctionReturn(0);
}
