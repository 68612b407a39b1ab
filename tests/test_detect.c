static const char help[] = "Tests of contact detection (src/detect/detect.c): the cell-list search against a brute-force O(N^2)\n"
                           "search on a polydisperse packing with walls, ownership over ranks (by grain id, through ghosts),\n"
                           "persistence of impulses, the alert distance, one-sided walls and segment ends, coincident\n"
                           "centres. (Its timing is a benchmark: scripts/bench_micro.c.)\n";

/* The scenes come from KergsSceneCreate with two materials and hand-set walls; their disks are given with
   KergsSceneSetDisks (the same full arrays on every rank, each rank keeps its contiguous slice as its owned
   disks), with grain ids set by the test on the owned disks. Detection builds the ghost layer itself. The
   reference for every check is a brute-force search over the disks gathered in global-index order. */
#include "testing.h"
#include "gathered_disks.h"

#define TOL 1e-12

/* A contact as the brute-force search sees it: a and b are global disk indices (b a wall index for a wall
   contact), a the disk of smaller grain id; ida, idb the grain ids (idb the wall index for a wall). */
typedef struct {
  PetscInt  a, kind, b;
  PetscReal gap, n[KERGS_DIM];
  PetscInt  ida, idb;
  PetscReal ra, rb, mu;
} Reference;

/* splitmix64: a small deterministic generator, identical on every rank. */
static PetscReal Uniform(unsigned long long *state)
{
  unsigned long long z = (*state += 0x9E3779B97F4A7C15ULL);

  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z = z ^ (z >> 31);
  return (PetscReal)(z >> 11) * (1.0 / 9007199254740992.0);
}

/* A scene without disks: two materials (friction table 0.3, 0.5 / 0.5, 0.1), nwalls walls to be set with
   SetWall, the alert distance given. */
static PetscErrorCode SceneCreate(MPI_Comm comm, PetscInt nwalls, PetscReal alert, KergsScene *scene)
{
  KergsScene s;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneCreate(comm, &s));
  PetscCall(PetscStrcpy(s->name, "test_detect"));
  PetscCall(PetscFree(s->density));
  PetscCall(PetscFree(s->mu));
  s->nmaterials = 2;
  PetscCall(PetscMalloc1(2, &s->density));
  s->density[0] = s->density[1] = 1.0;
  PetscCall(PetscMalloc1(4, &s->mu));
  s->mu[0] = 0.3;
  s->mu[1] = s->mu[2] = 0.5;
  s->mu[3]            = 0.1;
  s->nwalls           = nwalls;
  PetscCall(PetscCalloc1(nwalls + 1, &s->walls));
  s->alert = alert;
  *scene   = s;
  PetscFunctionReturn(0);
}

/* The n disks (full arrays x, r, the same on every rank), material i % 2, grain id id[i] (NULL: 1000 + i). */
static PetscErrorCode SceneSetDisks(KergsScene s, PetscInt n, const PetscReal x[], const PetscReal r[], const PetscInt id[])
{
  PetscInt *material;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(n + 1, &material));
  for (PetscInt i = 0; i < n; i++) material[i] = i % 2;
  PetscCall(KergsSceneSetDisks(s, n, x, r, material, NULL));
  PetscCall(PetscFree(material));
  PetscCheck(s->ndisks == n && s->nowned == s->dend - s->dstart, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "SetDisks: %" PetscInt_FMT " disks, %" PetscInt_FMT " owned", s->ndisks, s->nowned);
  for (PetscInt i = 0; i < s->nowned; i++) s->id[i] = id ? id[s->dstart + i] : 1000 + s->dstart + i;
  s->frictional = PETSC_TRUE;
  PetscFunctionReturn(0);
}

static PetscErrorCode SetWall(KergsScene s, PetscInt w, PetscBool infinite, PetscReal ax, PetscReal ay, PetscReal bx, PetscReal by,
                              PetscInt material)
{
  KergsWall *wall = &s->walls[w];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(wall->name, sizeof(wall->name), "wall%d", (int)w));
  wall->infinite = infinite;
  wall->a[0]     = ax;
  wall->a[1]     = ay;
  wall->b[0]     = bx;
  wall->b[1]     = by;
  wall->material = material;
  PetscFunctionReturn(0);
}

/* Random polydisperse disks in an L x L box (radius ratio 10, overlaps allowed: detection does not care,
   and overlaps give negative gaps), closed by a line, two segments and a line, plus a tilted segment and a
   tilted line across the inside so that disks lie on both sides of some walls and beyond segment ends.
   Grain ids are a scrambled permutation of the indices (1000 + 7919 i mod n), so that the disk of smaller id
   (body a, whose owner owns the contact) is often the one of larger index, and on another rank. */
static PetscErrorCode RandomPackingWithWalls(MPI_Comm comm, PetscInt ndisks, unsigned long long seed, KergsScene *scene)
{
  const PetscReal rmin = 0.1;
  PetscReal       area = 0.0, L, *x, *r;
  PetscInt       *id;
  KergsScene      s;

  PetscFunctionBeginUser;
  PetscCall(SceneCreate(comm, 6, 0.2 * rmin, &s));
  PetscCall(PetscMalloc3(KERGS_DIM * ndisks, &x, ndisks, &r, ndisks, &id));
  for (PetscInt i = 0; i < ndisks; i++) {
    const PetscReal u = Uniform(&seed);
    r[i]              = rmin * (1.0 + 9.0 * u * u * u);
    area += PETSC_PI * r[i] * r[i];
    id[i] = 1000 + (7919 * i) % ndisks;
  }
  L = PetscSqrtReal(area / 0.75);
  for (PetscInt i = 0; i < KERGS_DIM * ndisks; i++) x[i] = L * Uniform(&seed);
  PetscCall(SetWall(s, 0, PETSC_TRUE, 0, 0, 1, 0, 0));                          /* bottom line, normal +y */
  PetscCall(SetWall(s, 1, PETSC_FALSE, 0, L, 0, 0, 1));                         /* left segment, normal +x */
  PetscCall(SetWall(s, 2, PETSC_FALSE, 0.8 * L, L, 0.2 * L, L, 0));             /* part of the top, normal -y */
  PetscCall(SetWall(s, 3, PETSC_TRUE, L, 0, L, 1, 1));                          /* right line, normal -x */
  PetscCall(SetWall(s, 4, PETSC_FALSE, 0.3 * L, 0.3 * L, 0.7 * L, 0.5 * L, 1)); /* tilted segment inside */
  PetscCall(SetWall(s, 5, PETSC_TRUE, 0.0, 0.2 * L, 1.0, 0.2 * L - 0.25, 0));   /* tilted line inside */
  PetscCall(SceneSetDisks(s, ndisks, x, r, id));
  PetscCall(PetscFree3(x, r, id));
  *scene = s;
  PetscFunctionReturn(0);
}

static int CompareKeys(PetscInt a1, PetscInt k1, PetscInt b1, PetscInt a2, PetscInt k2, PetscInt b2)
{
  if (a1 != a2) return a1 < a2 ? -1 : 1;
  if (k1 != k2) return k1 < k2 ? -1 : 1;
  if (b1 != b2) return b1 < b2 ? -1 : 1;
  return 0;
}

/* Order of the contacts of one rank: (global index of a, kind, idb). */
static int CompareReferenceByIndex(const void *p, const void *q)
{
  const Reference *r = (const Reference *)p, *t = (const Reference *)q;
  return CompareKeys(r->a, r->kind, r->idb, t->a, t->kind, t->idb);
}

/* Rank-independent order: (grain id of a, kind, idb). */
static int CompareReferenceById(const void *p, const void *q)
{
  const Reference *r = (const Reference *)p, *t = (const Reference *)q;
  return CompareKeys(r->ida, r->kind, r->idb, t->ida, t->kind, t->idb);
}

static int CompareKeyTriples(const void *p, const void *q)
{
  const PetscInt *r = (const PetscInt *)p, *t = (const PetscInt *)q;
  return CompareKeys(r[0], r[1], r[2], t[0], t[1], t[2]);
}

/* The bookkeeping fields of a reference (a, kind, b set) from the gathered disks: ids, radii, friction. */
static void CompleteReference(KergsScene s, const Disks *g, Reference *r)
{
  const PetscInt mb = r->kind == KERGS_CONTACT_DISK_DISK ? g->material[r->b] : s->walls[r->b].material;

  r->ida = g->id[r->a];
  r->idb = r->kind == KERGS_CONTACT_DISK_DISK ? g->id[r->b] : r->b;
  r->ra  = g->radius[r->a];
  r->rb  = r->kind == KERGS_CONTACT_DISK_DISK ? g->radius[r->b] : 0.0;
  r->mu  = s->mu[g->material[r->a] * s->nmaterials + mb];
}

/* Every potential contact of the scene over all disks (gathered), by the O(N^2) definition, with body a the
   disk of smaller grain id, sorted by (global index of a, kind, idb): the order of the owned contacts of each
   rank, rank after rank. The wall test is written independently of detect.c: signed distance by the cross
   product (b - a) x (x - a) / |b - a|, and the segment test on the parameter of the projection in [0, 1]. */
static PetscErrorCode BruteForce(KergsScene s, Reference **ref, PetscInt *nref)
{
  PetscInt   n = 0, cap = 16;
  Reference *r;
  Disks      g;

  PetscFunctionBeginUser;
  PetscCall(DisksGather(s, &g));
  PetscCall(PetscMalloc1(cap, &r));
  for (PetscInt i = 0; i < g.n; i++) {
    const PetscReal *xi = &g.x[KERGS_DIM * i];
    for (PetscInt j = i + 1; j < g.n; j++) {
      const PetscReal *xj   = &g.x[KERGS_DIM * j];
      const PetscReal  dist = PetscSqrtReal((xi[0] - xj[0]) * (xi[0] - xj[0]) + (xi[1] - xj[1]) * (xi[1] - xj[1]));
      const PetscReal  gap  = dist - g.radius[i] - g.radius[j];
      const PetscInt   a = g.id[i] < g.id[j] ? i : j, b = a == i ? j : i;

      if (gap >= s->alert) continue;
      if (n == cap) PetscCall(PetscRealloc((size_t)(cap *= 2) * sizeof(Reference), &r));
      r[n].a    = a;
      r[n].kind = KERGS_CONTACT_DISK_DISK;
      r[n].b    = b;
      r[n].gap  = gap;
      r[n].n[0] = (g.x[KERGS_DIM * a] - g.x[KERGS_DIM * b]) / dist;
      r[n].n[1] = (g.x[KERGS_DIM * a + 1] - g.x[KERGS_DIM * b + 1]) / dist;
      CompleteReference(s, &g, &r[n]);
      n++;
    }
    for (PetscInt w = 0; w < s->nwalls; w++) {
      const KergsWall *wall = &s->walls[w];
      const PetscReal  ux = wall->b[0] - wall->a[0], uy = wall->b[1] - wall->a[1], len = PetscSqrtReal(ux * ux + uy * uy);
      const PetscReal  px = xi[0] - wall->a[0], py = xi[1] - wall->a[1];
      const PetscReal  d = (ux * py - uy * px) / len, lambda = (ux * px + uy * py) / (len * len);

      if (!(d > 0.0) || d - g.radius[i] >= s->alert) continue;
      if (!wall->infinite && (lambda < 0.0 || lambda > 1.0)) continue;
      if (n == cap) PetscCall(PetscRealloc((size_t)(cap *= 2) * sizeof(Reference), &r));
      r[n].a    = i;
      r[n].kind = KERGS_CONTACT_DISK_WALL;
      r[n].b    = w;
      r[n].gap  = d - g.radius[i];
      r[n].n[0] = -uy / len;
      r[n].n[1] = ux / len;
      CompleteReference(s, &g, &r[n]);
      n++;
    }
  }
  qsort(r, (size_t)n, sizeof(Reference), CompareReferenceByIndex);
  PetscCall(DisksFree(&g));
  *ref  = r;
  *nref = n;
  PetscFunctionReturn(0);
}

/* What can be wrong with a contact against its reference, counted over contacts (ContactFaults). */
enum {
  FAULT_BODIES, /* a not an owned disk, b not a local disk, or not the reference's bodies and kind */
  FAULT_IDS,    /* grain ids of a and b */
  FAULT_GAP,
  FAULT_NORM,   /* |n| != 1 */
  FAULT_NORMAL, /* n differs from the reference */
  FAULT_SIDE,   /* n does not point from b towards a */
  FAULT_TANGENT,
  FAULT_RADII,
  FAULT_MU,
  NFAULTS
};
static const char *const FaultNames[NFAULTS] = {"bodies a, b and kind as brute force",
                                                "grain ids as brute force",
                                                "gaps as brute force (to 1e-12)",
                                                "|n| = 1",
                                                "normals as brute force (to 1e-12)",
                                                "n points from b to a",
                                                "t = (-n_y, n_x)",
                                                "radii as brute force",
                                                "friction coefficients as brute force"};

/* Geometry and bookkeeping of one contact against its reference: a is an owned disk, b a local disk (owned or
   ghost) or a wall, both the reference's bodies (global index and grain id), n, t, gap, radii, mu as expected.
   Adds one to fault[f] for each wrong property f (the rest is not looked at when the bodies are out of range). */
static void ContactFaults(KergsScene s, const KergsContact *c, const Reference *ref, PetscInt fault[NFAULTS])
{
  const PetscReal nnorm = PetscSqrtReal(c->n[0] * c->n[0] + c->n[1] * c->n[1]);
  const PetscBool disk  = (PetscBool)(c->kind == KERGS_CONTACT_DISK_DISK);
  PetscReal       along;

  if (!(0 <= c->a && c->a < s->nowned) || (disk && !(0 <= c->b && c->b < s->nlocal)) || (!disk && !(0 <= c->b && c->b < s->nwalls))) {
    fault[FAULT_BODIES]++;
    return;
  }
  if (!(s->gidx[c->a] == ref->a && (PetscInt)c->kind == ref->kind && (disk ? s->gidx[c->b] : c->b) == ref->b)) fault[FAULT_BODIES]++;
  if (!(s->id[c->a] == ref->ida && c->idb == ref->idb && (!disk || s->id[c->b] == c->idb))) fault[FAULT_IDS]++;
  if (!(PetscAbsReal(c->gap - ref->gap) <= TOL)) fault[FAULT_GAP]++;
  if (!(PetscAbsReal(nnorm - 1.0) <= TOL)) fault[FAULT_NORM]++;
  if (!(PetscAbsReal(c->n[0] - ref->n[0]) <= TOL && PetscAbsReal(c->n[1] - ref->n[1]) <= TOL)) fault[FAULT_NORMAL]++;
  /* n points from b towards a: for a disk pair along x_a - x_b (local copies: b may be a ghost, whose position
     must be current), for a wall towards the centre's side */
  if (disk)
    along = c->n[0] * (s->x[2 * c->a] - s->x[2 * c->b]) + c->n[1] * (s->x[2 * c->a + 1] - s->x[2 * c->b + 1]);
  else
    along = c->n[0] * (s->x[2 * c->a] - s->walls[c->b].a[0]) + c->n[1] * (s->x[2 * c->a + 1] - s->walls[c->b].a[1]);
  if (!(along > 0.0)) fault[FAULT_SIDE]++;
  if (!(c->t[0] == -c->n[1] && c->t[1] == c->n[0])) fault[FAULT_TANGENT]++;
  if (!(c->ra == ref->ra && c->rb == ref->rb)) fault[FAULT_RADII]++;
  if (!(c->mu == ref->mu)) fault[FAULT_MU]++;
}

/* One Check line per property: the number of contacts (summed over comm) that get it wrong. Collective. */
static PetscErrorCode CheckFaults(MPI_Comm comm, const char label[], PetscInt fault[NFAULTS])
{
  PetscFunctionBeginUser;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, fault, NFAULTS, MPIU_INT, MPI_SUM, comm));
  for (PetscInt f = 0; f < NFAULTS; f++)
    PetscCall(Checkf((PetscBool)(fault[f] == 0), fault[f], 0, "%s: %s (contacts not)", label, FaultNames[f]));
  PetscFunctionReturn(0);
}

/* The contacts of this rank are exactly the brute-force contacts whose disk a (smaller grain id; the disk of a
   wall contact) it owns, in (a, kind, idb) order; nglobal and start agree. Gathered over the ranks, the keys
   (grain id of a, kind, grain id of b) are exactly the brute-force list of the whole scene (the 1-rank answer):
   each contact found on exactly one rank, none missing. Returns, summed over ranks, the numbers of disk-disk
   contacts whose body b is a ghost, whose a has the larger global index, and both (cut pairs owned by the rank
   of the higher indices, because its disk has the smaller grain id). */
static PetscErrorCode CheckAgainstBruteForce(KergsContacts ct, KergsScene s, const char label[], PetscInt stats[3])
{
  Reference  *ref  = NULL;
  PetscInt    nref = 0, first = 0, nall, *keys, *allkeys, cnt[3] = {0, 0, 0}, fault[NFAULTS] = {0}, unordered = 0, repeated = 0, differ = 0;
  PetscMPIInt size, rank, *counts, *displs, nkeys;
  PetscBool   counted;
  char        what[256];

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(BruteForce(s, &ref, &nref));
  while (first < nref && ref[first].a < s->dstart) first++;
  PetscCall(Checkf((PetscBool)(ct->nglobal == nref), ct->nglobal, nref, "%s: number of contacts = brute force", label));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: each rank's first contact index = brute force", label));
  PetscCall(CheckAll(s->comm, (PetscBool)(ct->start == first), what, ct->start, first));
  counted = (PetscBool)(first + ct->n <= nref && (first + ct->n == nref || ref[first + ct->n].a >= s->dend));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: each rank has the brute-force contacts it owns (count)", label));
  PetscCall(CheckAll(s->comm, counted, what, ct->n, counted ? ct->n : -1));
  if (counted) { /* ref[first + k] exists */
    for (PetscInt k = 0; k < ct->n; k++) {
      const KergsContact *c = &ct->c[k];

      if (k > 0 && CompareKeys(ct->c[k - 1].a, ct->c[k - 1].kind, ct->c[k - 1].idb, c->a, c->kind, c->idb) >= 0) unordered++;
      ContactFaults(s, c, &ref[first + k], fault);
      if (c->kind == KERGS_CONTACT_DISK_DISK && 0 <= c->b && c->b < s->nlocal && 0 <= c->a && c->a < s->nowned) {
        cnt[0] += c->b >= s->nowned;
        cnt[1] += s->gidx[c->b] < s->gidx[c->a];
        cnt[2] += c->b >= s->nowned && s->gidx[c->b] < s->gidx[c->a];
      }
    }
    PetscCall(CheckFaults(s->comm, label, fault));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &unordered, 1, MPIU_INT, MPI_SUM, s->comm));
  PetscCall(Checkf((PetscBool)(unordered == 0), unordered, 0, "%s: contacts in (a, kind, idb) order (pairs out of order)", label));
  /* gather every rank's keys by grain ids: the union must be the brute-force list with no repeats */
  PetscCall(PetscMalloc1(3 * ct->n + 1, &keys));
  for (PetscInt k = 0; k < ct->n; k++) {
    keys[3 * k]     = 0 <= ct->c[k].a && ct->c[k].a < s->nowned ? s->id[ct->c[k].a] : -1;
    keys[3 * k + 1] = ct->c[k].kind;
    keys[3 * k + 2] = ct->c[k].idb;
  }
  PetscCall(PetscMalloc2(size, &counts, size + 1, &displs));
  PetscCall(PetscMPIIntCast(3 * ct->n, &nkeys));
  PetscCallMPI(MPI_Allgather(&nkeys, 1, MPI_INT, counts, 1, MPI_INT, s->comm));
  displs[0] = 0;
  for (PetscMPIInt p = 0; p < size; p++) displs[p + 1] = displs[p] + counts[p];
  PetscCall(PetscMalloc1(displs[size] + 1, &allkeys));
  PetscCallMPI(MPI_Allgatherv(keys, nkeys, MPIU_INT, allkeys, counts, displs, MPIU_INT, s->comm));
  nall = displs[size] / 3;
  PetscCall(Checkf((PetscBool)(nall == nref), nall, nref, "%s: contacts over all ranks = brute force", label));
  qsort(allkeys, (size_t)nall, 3 * sizeof(PetscInt), CompareKeyTriples);
  qsort(ref, (size_t)nref, sizeof(Reference), CompareReferenceById);
  for (PetscInt k = 0; k < PetscMin(nall, nref); k++) {
    if (k > 0 && CompareKeyTriples(&allkeys[3 * (k - 1)], &allkeys[3 * k]) == 0) repeated++;
    if (CompareKeys(allkeys[3 * k], allkeys[3 * k + 1], allkeys[3 * k + 2], ref[k].ida, ref[k].kind, ref[k].idb) != 0) differ++;
  }
  PetscCall(Checkf((PetscBool)(repeated == 0), repeated, 0, "%s: each contact found on one rank only (repeats)", label));
  PetscCall(Checkf((PetscBool)(differ == 0), differ, 0, "%s: gathered keys = brute-force keys (differing)", label));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, cnt, 3, MPIU_INT, MPI_SUM, s->comm));
  if (stats)
    for (PetscInt i = 0; i < 3; i++) stats[i] = cnt[i];
  PetscCall(PetscPrintf(s->comm,
                        "%s: %" PetscInt_FMT " contacts on %d rank(s) (%" PetscInt_FMT " with a ghost b, %" PetscInt_FMT
                        " owned by the disk of larger index and smaller id, %" PetscInt_FMT " both)\n",
                        label, nref, (int)size, cnt[0], cnt[1], cnt[2]));
  PetscCall(PetscFree(allkeys));
  PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree(keys));
  PetscCall(PetscFree(ref));
  PetscFunctionReturn(0);
}

/* A known impulse per pair (by grain ids), to see it carried over. */
static PetscReal PairImpulse(PetscInt ida, PetscInt kind, PetscInt idb, PetscInt comp)
{
  return (comp == 0 ? 1.0 : -0.5) * (1.0 + 1e-3 * (PetscReal)ida + 1e-7 * (PetscReal)idb + 0.25 * (PetscReal)kind);
}

/* Move every disk (the same draws on any number of ranks: one per global index and component, applied by the
   owner) by up to step / 2 per component, then refresh the ghosts as the stepper does after its update. */
static PetscErrorCode MoveDisks(KergsScene s, PetscReal step, unsigned long long *seed)
{
  PetscFunctionBeginUser;
  for (PetscInt g = 0; g < s->ndisks; g++)
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      const PetscReal delta = step * (Uniform(seed) - 0.5);
      if (s->dstart <= g && g < s->dend) s->x[KERGS_DIM * (g - s->dstart) + d] += delta;
    }
  PetscCall(KergsSceneRefreshGhosts(s));
  PetscFunctionReturn(0);
}

/* The impulses carried over by the last detection: a contact whose key (grain id of a, kind, idb) was in
   oldkeys (sorted) is persistent with PairImpulse, any other is fresh. counts: kept, new. */
static PetscErrorCode CheckPersistence(const char label[], KergsContacts ct, KergsScene s, const PetscInt oldkeys[], PetscInt nold,
                                       PetscInt counts[2])
{
  PetscInt wrong[2] = {0, 0}; /* persistent flags, impulses */

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < ct->n; k++) {
    const KergsContact *c      = &ct->c[k];
    const PetscInt      key[3] = {s->id[c->a], c->kind, c->idb};
    const PetscBool     was = (PetscBool)(nold > 0 && bsearch(key, oldkeys, (size_t)nold, 3 * sizeof(PetscInt), CompareKeyTriples) != NULL);

    if (c->persistent != was) wrong[0]++;
    for (PetscInt d = 0; d < KERGS_MAXCOMP; d++)
      if (c->r[d] != (was ? PairImpulse(key[0], c->kind, c->idb, d) : 0.0)) {
        wrong[1]++;
        break;
      }
    counts[was ? 0 : 1]++;
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, wrong, 2, MPIU_INT, MPI_SUM, s->comm));
  PetscCall(
      Checkf((PetscBool)(wrong[0] == 0), wrong[0], 0, "%s: persistent flag set exactly on the pairs seen before (contacts not)", label));
  PetscCall(Checkf((PetscBool)(wrong[1] == 0), wrong[1], 0, "%s: impulses carried over, zero for new pairs (contacts not)", label));
  PetscFunctionReturn(0);
}

/* Impulses as a solver would leave them (PairImpulse), velocities that must not survive; the sorted keys. */
static PetscErrorCode SetImpulses(KergsContacts ct, KergsScene s, PetscInt **oldkeys, PetscInt *nold)
{
  PetscFunctionBeginUser;
  *nold = ct->n;
  PetscCall(PetscMalloc1(3 * ct->n + 1, oldkeys));
  for (PetscInt k = 0; k < ct->n; k++) {
    KergsContact *c = &ct->c[k];
    for (PetscInt d = 0; d < KERGS_MAXCOMP; d++) {
      c->r[d] = PairImpulse(s->id[c->a], c->kind, c->idb, d);
    }
    (*oldkeys)[3 * k]     = s->id[c->a];
    (*oldkeys)[3 * k + 1] = c->kind;
    (*oldkeys)[3 * k + 2] = c->idb;
  }
  qsort(*oldkeys, (size_t)*nold, 3 * sizeof(PetscInt), CompareKeyTriples);
  PetscFunctionReturn(0);
}

static PetscErrorCode TestPackingAndPersistence(MPI_Comm comm)
{
  const PetscInt     ndisks = 3000;
  KergsScene         s      = NULL;
  KergsContacts      ct     = NULL;
  PetscInt           nold, *oldkeys, counts[2] = {0, 0}, gcounts[2], nwall = 0, nstale = 0, stats[3], rebuilds;
  PetscMPIInt        size;
  unsigned long long seed = 12345;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(RandomPackingWithWalls(comm, ndisks, 2024, &s));
  PetscCall(KergsContactsCreate(comm, &ct));
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(CheckAgainstBruteForce(ct, s, "polydisperse packing with walls", stats));
  /* ownership follows the grain ids, not the indices; on several ranks, cut pairs are seen through ghosts and owned
     by either side */
  PetscCall(Checkf((PetscBool)(stats[1] > 0 && (size == 1 || (stats[2] > 0 && stats[0] - stats[2] > 0))), stats[1], 1,
                   "ownership by grain id exercised: contacts owned by the disk of larger index (%" PetscInt_FMT " across ranks)",
                   stats[2]));
  for (PetscInt k = 0; k < ct->n; k++) {
    if (ct->c[k].persistent || ct->c[k].r[0] != 0.0 || ct->c[k].r[1] != 0.0) nstale++;
    nwall += ct->c[k].kind == KERGS_CONTACT_DISK_WALL;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nwall, 1, MPIU_INT, MPI_SUM, comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nstale, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(Check((PetscBool)(nstale == 0), "first detection: every contact fresh, r = 0 and not persistent (contacts not)", nstale, 0));
  PetscCall(Check((PetscBool)(nwall >= 20), "the walls are exercised (disk-wall contacts)", nwall, 20));

  /* move every disk by up to 0.03 (radii 0.1 .. 1): some pairs part, others meet; the ghost layer is rebuilt */
  PetscCall(SetImpulses(ct, s, &oldkeys, &nold));
  PetscCall(MoveDisks(s, 0.06, &seed));
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(CheckAgainstBruteForce(ct, s, "after a small move", NULL));
  PetscCall(CheckPersistence("after a small move", ct, s, oldkeys, nold, counts));
  PetscCallMPI(MPI_Allreduce(counts, gcounts, 2, MPIU_INT, MPI_SUM, comm));
  PetscCall(Checkf((PetscBool)(gcounts[0] > 0 && gcounts[1] > 0 && gcounts[0] + gcounts[1] == ct->nglobal),
                   PetscMin(gcounts[0], gcounts[1]), 1,
                   "after a small move: persistence exercised (%" PetscInt_FMT " pairs kept, %" PetscInt_FMT " new: the fewer)", gcounts[0],
                   gcounts[1]));
  PetscCall(PetscFree(oldkeys));

  /* a move well within half the ghost skin (the alert distance 0.02): the layer is kept, its ghosts refreshed, and
     detection stays exact; every pair that still touches keeps its impulse */
  rebuilds = s->ghost_rebuilds;
  PetscCall(SetImpulses(ct, s, &oldkeys, &nold));
  PetscCall(MoveDisks(s, 0.004, &seed));
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(CheckAll(comm, (PetscBool)(size == 1 || s->ghost_rebuilds == rebuilds),
                     "tiny move (<= 0.003): the ghost layer is kept (builds so far)", s->ghost_rebuilds, rebuilds));
  PetscCall(CheckAgainstBruteForce(ct, s, "after a tiny move (ghosts refreshed, not rebuilt)", NULL));
  counts[0] = counts[1] = 0;
  PetscCall(CheckPersistence("after a tiny move", ct, s, oldkeys, nold, counts));
  PetscCallMPI(MPI_Allreduce(counts, gcounts, 2, MPIU_INT, MPI_SUM, comm));
  PetscCall(Check((PetscBool)(gcounts[0] > 0), "after a tiny move: pairs that kept their impulse", gcounts[0], 1));
  PetscCall(PetscFree(oldkeys));
  PetscCall(KergsContactsDestroy(&ct));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* Hand-placed disks (radius 1, alert 0.1) on every rank alone: pairs and wall contacts just inside and
   just outside the alert distance, a centre behind a one-sided wall, centres beyond the ends of a
   segment, and one disk far away (the grid must stay small). */
static PetscErrorCode TestAlertAndWalls(void)
{
  const PetscReal eps = 1e-9, alert = 0.1;
  const PetscReal pos[][2] = {
      {0.0, 10.0},       {2.1 - eps, 10.0}, /* gap alert - eps with disk 0: contact */
      {0.0, 20.0},       {2.1 + eps, 20.0}, /* gap alert + eps with disk 2: none */
      {50.0, 1.1 - eps},                    /* above the bottom line, gap alert - eps: contact */
      {60.0, 1.1 + eps},                    /* gap alert + eps: none */
      {70.0, -0.5},                         /* centre behind the bottom line, overlapping it: none (one-sided) */
      {201.05, 5.0},                        /* beside the segment x = 200, y in [0, 10], gap 0.05: contact */
      {201.05, 10.5},                       /* beyond the segment's end a: none */
      {201.05, -0.5},                       /* beyond the end b (and behind the bottom line): none */
      {1.0e6, 1.0e6},                       /* far away */
  };
  const PetscInt ndisks   = (PetscInt)(sizeof(pos) / sizeof(pos[0]));
  Reference      expect[] = {
           {0, KERGS_CONTACT_DISK_DISK, 1, 0.1 - eps, {-1.0, 0.0}, 0, 0, 0, 0, 0},
           {4, KERGS_CONTACT_DISK_WALL, 0, 0.1 - eps, {0.0, 1.0}, 0, 0, 0, 0, 0},
           {7, KERGS_CONTACT_DISK_WALL, 1, 0.05, {1.0, 0.0}, 0, 0, 0, 0, 0},
  };
  PetscReal     x[2 * (sizeof(pos) / sizeof(pos[0]))], r[sizeof(pos) / sizeof(pos[0])];
  KergsScene    s;
  KergsContacts ct;
  Disks         g;

  PetscFunctionBeginUser;
  PetscCall(SceneCreate(PETSC_COMM_SELF, 2, alert, &s));
  for (PetscInt i = 0; i < ndisks; i++) {
    x[2 * i]     = pos[i][0];
    x[2 * i + 1] = pos[i][1];
    r[i]         = 1.0;
  }
  PetscCall(SetWall(s, 0, PETSC_TRUE, 0, 0, 1, 0, 0));       /* bottom line, normal +y */
  PetscCall(SetWall(s, 1, PETSC_FALSE, 200, 10, 200, 0, 1)); /* segment, normal +x */
  PetscCall(SceneSetDisks(s, ndisks, x, r, NULL));
  PetscCall(DisksGather(s, &g));
  for (PetscInt k = 0; k < 3; k++) CompleteReference(s, &g, &expect[k]);
  PetscCall(DisksFree(&g));
  PetscCall(KergsContactsCreate(PETSC_COMM_SELF, &ct));
  PetscCall(KergsContactsDetect(ct, s));
  /* every rank runs this alone (PETSC_COMM_SELF) on the same disks: the values agree on every rank */
  PetscCall(Check((PetscBool)(ct->n == 3 && ct->nglobal == 3 && ct->start == 0),
                  "alert 0.1: contacts at gap alert - 1e-9 kept, alert + 1e-9 dropped, one-sided wall, segment ends", ct->n, 3));
  if (ct->n == 3) {
    PetscInt fault[NFAULTS] = {0};
    for (PetscInt k = 0; k < 3; k++) ContactFaults(s, &ct->c[k], &expect[k], fault);
    PetscCall(CheckFaults(PETSC_COMM_SELF, "alert 0.1", fault));
  }
  PetscCall(Check((PetscBool)(ct->ncellx * ct->ncelly <= 4 * ndisks + 64), "a far disk keeps the grid small (cells)",
                  ct->ncellx * ct->ncelly, 4 * ndisks + 64));

  /* the same object again with a shrunk alert: the two contacts at gap 0.1 - eps drop out */
  s->alert = 0.1 - 2 * eps;
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(Check((PetscBool)(ct->n == 1 && ct->c[0].a == 7), "alert 0.1 - 2e-9: only the contact at gap 0.05 is left", ct->n, 1));
  PetscCall(Check((PetscBool)(ct->n >= 1 && ct->c[0].persistent), "alert 0.1 - 2e-9: the kept wall contact is persistent",
                  ct->n >= 1 && ct->c[0].persistent, 1));
  PetscCall(KergsContactsDestroy(&ct));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* Two disks on the same centre have no normal: detection must fail and name both grains. */
static PetscErrorCode TestCoincidentCentres(void)
{
  KergsScene      s;
  KergsContacts   ct;
  PetscErrorCode  ierr;
  char           *message = NULL, *has1, *has2;
  const PetscReal x[6] = {5.0, 0.0, 0.0, 0.0, 0.0, 0.0}, r[3] = {0.5, 0.5, 0.5};

  PetscFunctionBeginUser;
  PetscCall(SceneCreate(PETSC_COMM_SELF, 0, 0.0, &s));
  PetscCall(SceneSetDisks(s, 3, x, r, NULL)); /* disk 0 apart, disks 1 and 2 at the origin; grains 1000, 1001, 1002 */
  PetscCall(KergsContactsCreate(PETSC_COMM_SELF, &ct));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KergsContactsDetect(ct, s);
  PetscCall(PetscPopErrorHandler());
  PetscCall(Check((PetscBool)(ierr == PETSC_ERR_ARG_WRONG), "coincident centres: detection fails with PETSC_ERR_ARG_WRONG", ierr,
                  PETSC_ERR_ARG_WRONG));
  PetscCall(PetscErrorMessage(ierr, NULL, &message));
  has1 = has2 = NULL;
  if (message) PetscCall(PetscStrstr(message, "1001", &has1));
  if (message) PetscCall(PetscStrstr(message, "1002", &has2));
  PetscCall(Checkf((PetscBool)(has1 && has2), has1 && has2, 1, "coincident centres: the message names grains 1001 and 1002 [%s]",
                   message ? message : ""));
  PetscCall(KergsContactsDestroy(&ct));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCall(TestPackingAndPersistence(PETSC_COMM_WORLD));
  PetscCall(TestAlertAndWalls());
  PetscCall(TestCoincidentCentres());
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
