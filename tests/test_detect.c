static const char help[] = "Tests of contact detection (src/detect.c): the cell-list search against a brute-force O(N^2)\n"
                           "search on a polydisperse packing with walls, ownership over ranks (by grain id, through ghosts),\n"
                           "persistence of impulses, the alert distance, one-sided walls and segment ends, coincident\n"
                           "centres. (Its timing is a benchmark: scripts/bench_micro.c.)\n";

/* The scenes come from KergsSceneCreate with two materials and hand-set walls; their disks are given with
   KergsSceneSetDisks (the same full arrays on every rank, each rank keeps its contiguous slice as its owned
   disks), with grain ids set by the test on the owned disks. Detection builds the ghost layer itself. The
   reference for every check is a brute-force search over the disks gathered in global-index order. */
#include "internals.h"
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
  PetscCheck(s->ndisks == n && s->nowned == s->dend - s->dstart, PETSC_COMM_SELF, PETSC_ERR_PLIB, "SetDisks: %" PetscInt_FMT " disks, %" PetscInt_FMT " owned",
             s->ndisks, s->nowned);
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
  Disks     g;

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

/* Geometry and bookkeeping of one contact against its reference: a is an owned disk, b a local disk (owned or
   ghost) or a wall, both the reference's bodies (global index and grain id), n, t, gap, radii, mu as expected. */
static PetscErrorCode CheckContact(KergsScene s, const KergsContact *c, const Reference *ref, PetscInt k)
{
  const PetscReal nnorm = PetscSqrtReal(c->n[0] * c->n[0] + c->n[1] * c->n[1]);
  const PetscBool disk  = (PetscBool)(c->kind == KERGS_CONTACT_DISK_DISK);
  PetscReal       along;

  PetscFunctionBeginUser;
  PetscCheck(0 <= c->a && c->a < s->nowned, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT ": body a = %" PetscInt_FMT " is not an owned disk (%" PetscInt_FMT " owned)", k, c->a, s->nowned);
  PetscCheck(!disk || (0 <= c->b && c->b < s->nlocal), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT ": body b = %" PetscInt_FMT " is not a local disk (%" PetscInt_FMT " local)", k, c->b, s->nlocal);
  PetscCheck(s->gidx[c->a] == ref->a && (PetscInt)c->kind == ref->kind && (disk ? s->gidx[c->b] : c->b) == ref->b, PETSC_COMM_SELF,
             PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT " is (disk %" PetscInt_FMT ", %d, %s %" PetscInt_FMT "), brute force says (%" PetscInt_FMT
             ", %" PetscInt_FMT ", %" PetscInt_FMT ")",
             k, s->gidx[c->a], (int)c->kind, disk ? "disk" : "wall", disk ? s->gidx[c->b] : c->b, ref->a, ref->kind, ref->b);
  PetscCheck(s->id[c->a] == ref->ida && c->idb == ref->idb && (!disk || s->id[c->b] == c->idb), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT ": grain ids (%" PetscInt_FMT ", idb %" PetscInt_FMT "), brute force (%" PetscInt_FMT ", %" PetscInt_FMT ")",
             k, s->id[c->a], c->idb, ref->ida, ref->idb);
  PetscCheck(PetscAbsReal(c->gap - ref->gap) <= TOL, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT ": gap %.17g, brute force %.17g", k, (double)c->gap, (double)ref->gap);
  PetscCheck(PetscAbsReal(nnorm - 1.0) <= TOL, PETSC_COMM_SELF, PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": |n| = %.17g", k, (double)nnorm);
  PetscCheck(PetscAbsReal(c->n[0] - ref->n[0]) <= TOL && PetscAbsReal(c->n[1] - ref->n[1]) <= TOL, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT ": n = (%g, %g), brute force (%g, %g)", k, (double)c->n[0], (double)c->n[1], (double)ref->n[0],
             (double)ref->n[1]);
  /* n points from b towards a: for a disk pair along x_a - x_b (local copies: b may be a ghost, whose position
     must be current), for a wall towards the centre's side */
  if (disk)
    along = c->n[0] * (s->x[2 * c->a] - s->x[2 * c->b]) + c->n[1] * (s->x[2 * c->a + 1] - s->x[2 * c->b + 1]);
  else
    along = c->n[0] * (s->x[2 * c->a] - s->walls[c->b].a[0]) + c->n[1] * (s->x[2 * c->a + 1] - s->walls[c->b].a[1]);
  PetscCheck(along > 0.0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": normal does not point from b to a", k);
  PetscCheck(c->t[0] == -c->n[1] && c->t[1] == c->n[0], PETSC_COMM_SELF, PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": t is not (-n_y, n_x)",
             k);
  PetscCheck(c->ra == ref->ra && c->rb == ref->rb, PETSC_COMM_SELF, PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": wrong radii", k);
  PetscCheck(c->mu == ref->mu, PETSC_COMM_SELF, PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": wrong friction coefficient", k);
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
  PetscInt    nref = 0, first = 0, nall, *keys, *allkeys, cnt[3] = {0, 0, 0};
  PetscMPIInt size, rank, *counts, *displs, nkeys;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(BruteForce(s, &ref, &nref));
  while (first < nref && ref[first].a < s->dstart) first++;
  PetscCheck(ct->nglobal == nref, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: nglobal %" PetscInt_FMT ", brute force finds %" PetscInt_FMT, label,
             ct->nglobal, nref);
  PetscCheck(ct->start == first, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: start %" PetscInt_FMT ", expected %" PetscInt_FMT, label, ct->start,
             first);
  PetscCheck(first + ct->n <= nref && (first + ct->n == nref || ref[first + ct->n].a >= s->dend), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: %" PetscInt_FMT " local contacts, not the brute-force count of the contacts owned here", label, ct->n);
  for (PetscInt k = 0; k < ct->n; k++) {
    const KergsContact *c = &ct->c[k];

    if (k > 0)
      PetscCheck(CompareKeys(ct->c[k - 1].a, ct->c[k - 1].kind, ct->c[k - 1].idb, c->a, c->kind, c->idb) < 0, PETSC_COMM_SELF,
                 PETSC_ERR_PLIB, "%s: contacts %" PetscInt_FMT " and %" PetscInt_FMT " out of (a, kind, idb) order", label, k - 1, k);
    PetscCall(CheckContact(s, c, &ref[first + k], k));
    if (c->kind == KERGS_CONTACT_DISK_DISK) {
      cnt[0] += c->b >= s->nowned;
      cnt[1] += s->gidx[c->b] < s->gidx[c->a];
      cnt[2] += c->b >= s->nowned && s->gidx[c->b] < s->gidx[c->a];
    }
  }
  /* gather every rank's keys by grain ids: the union must be the brute-force list with no repeats */
  PetscCall(PetscMalloc1(3 * ct->n + 1, &keys));
  for (PetscInt k = 0; k < ct->n; k++) {
    keys[3 * k]     = s->id[ct->c[k].a];
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
  PetscCheck(nall == nref, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: %" PetscInt_FMT " contacts over all ranks, brute force %" PetscInt_FMT,
             label, nall, nref);
  qsort(allkeys, (size_t)nall, 3 * sizeof(PetscInt), CompareKeyTriples);
  qsort(ref, (size_t)nref, sizeof(Reference), CompareReferenceById);
  for (PetscInt k = 0; k < nall; k++) {
    PetscCheck(k == 0 || CompareKeyTriples(&allkeys[3 * (k - 1)], &allkeys[3 * k]) != 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: contact (grain %" PetscInt_FMT ", %" PetscInt_FMT ", %" PetscInt_FMT ") found on more than one rank", label, allkeys[3 * k],
               allkeys[3 * k + 1], allkeys[3 * k + 2]);
    PetscCheck(CompareKeys(allkeys[3 * k], allkeys[3 * k + 1], allkeys[3 * k + 2], ref[k].ida, ref[k].kind, ref[k].idb) == 0, PETSC_COMM_SELF,
               PETSC_ERR_PLIB,
               "%s: gathered contact %" PetscInt_FMT " (grain %" PetscInt_FMT ", %" PetscInt_FMT ", %" PetscInt_FMT
               ") differs from brute force (grain %" PetscInt_FMT ", %" PetscInt_FMT ", %" PetscInt_FMT ")",
               label, k, allkeys[3 * k], allkeys[3 * k + 1], allkeys[3 * k + 2], ref[k].ida, ref[k].kind, ref[k].idb);
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, cnt, 3, MPIU_INT, MPI_SUM, s->comm));
  if (stats)
    for (PetscInt i = 0; i < 3; i++) stats[i] = cnt[i];
  PetscCall(PetscPrintf(s->comm,
                        "%s: %" PetscInt_FMT " contacts match brute force (pairs, gaps and normals to %g) on %d rank(s), each found once"
                        " (%" PetscInt_FMT " with a ghost b, %" PetscInt_FMT " owned by the disk of larger index and smaller id, %" PetscInt_FMT
                        " both)\n",
                        label, nref, (double)TOL, (int)size, cnt[0], cnt[1], cnt[2]));
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
static PetscErrorCode CheckPersistence(KergsContacts ct, KergsScene s, const PetscInt oldkeys[], PetscInt nold, PetscInt counts[2])
{
  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < ct->n; k++) {
    const KergsContact *c      = &ct->c[k];
    const PetscInt      key[3] = {s->id[c->a], c->kind, c->idb};
    const PetscBool     was    = (PetscBool)(nold > 0 && bsearch(key, oldkeys, (size_t)nold, 3 * sizeof(PetscInt), CompareKeyTriples) != NULL);

    PetscCheck(c->persistent == was, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "contact (grain %" PetscInt_FMT ", %d, %" PetscInt_FMT "): persistent flag %d, expected %d", key[0], (int)c->kind, c->idb,
               (int)c->persistent, (int)was);
    for (PetscInt d = 0; d < KERGS_MAXCOMP; d++) {
      const PetscReal expect = was ? PairImpulse(key[0], c->kind, c->idb, d) : 0.0;
      PetscCheck(c->r[d] == expect, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "contact (grain %" PetscInt_FMT ", %d, %" PetscInt_FMT "): r[%" PetscInt_FMT "] = %g, expected %g", key[0], (int)c->kind,
                 c->idb, d, (double)c->r[d], (double)expect);
    }
    counts[was ? 0 : 1]++;
  }
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
  PetscInt           nold, *oldkeys, counts[2] = {0, 0}, gcounts[2], nwall = 0, stats[3], rebuilds;
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
  PetscCheck(stats[1] > 0 && (size == 1 || (stats[2] > 0 && stats[0] - stats[2] > 0)), comm, PETSC_ERR_PLIB,
             "%d ranks: %" PetscInt_FMT " contacts with a ghost b, %" PetscInt_FMT " owned by the disk of larger index, %" PetscInt_FMT
             " both: ownership by grain id (across ranks) not exercised",
             (int)size, stats[0], stats[1], stats[2]);
  for (PetscInt k = 0; k < ct->n; k++) {
    PetscCheck(!ct->c[k].persistent && ct->c[k].r[0] == 0.0 && ct->c[k].r[1] == 0.0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "first detection: contact %" PetscInt_FMT " not fresh", k);
    nwall += ct->c[k].kind == KERGS_CONTACT_DISK_WALL;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nwall, 1, MPIU_INT, MPI_SUM, comm));
  PetscCheck(nwall >= 20, comm, PETSC_ERR_PLIB, "only %" PetscInt_FMT " disk-wall contacts: the walls are not exercised", nwall);
  PetscCall(
      PetscPrintf(comm, "first detection: every contact fresh (r = 0, not persistent), %" PetscInt_FMT " disk-wall contacts\n", nwall));

  /* move every disk by up to 0.03 (radii 0.1 .. 1): some pairs part, others meet; the ghost layer is rebuilt */
  PetscCall(SetImpulses(ct, s, &oldkeys, &nold));
  PetscCall(MoveDisks(s, 0.06, &seed));
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(CheckAgainstBruteForce(ct, s, "after a small move", NULL));
  PetscCall(CheckPersistence(ct, s, oldkeys, nold, counts));
  PetscCallMPI(MPI_Allreduce(counts, gcounts, 2, MPIU_INT, MPI_SUM, comm));
  PetscCheck(gcounts[0] > 0 && gcounts[1] > 0 && gcounts[0] + gcounts[1] == ct->nglobal, comm, PETSC_ERR_PLIB,
             "persistence not exercised: %" PetscInt_FMT " kept, %" PetscInt_FMT " new", gcounts[0], gcounts[1]);
  PetscCall(PetscPrintf(
      comm, "persistence: %" PetscInt_FMT " pairs kept their impulse, %" PetscInt_FMT " new pairs start from zero, flags right\n",
      gcounts[0], gcounts[1]));
  PetscCall(PetscFree(oldkeys));

  /* a move well within half the ghost skin (the alert distance 0.02): the layer is kept, its ghosts refreshed, and
     detection stays exact; every pair that still touches keeps its impulse */
  rebuilds = s->ghost_rebuilds;
  PetscCall(SetImpulses(ct, s, &oldkeys, &nold));
  PetscCall(MoveDisks(s, 0.004, &seed));
  PetscCall(KergsContactsDetect(ct, s));
  PetscCheck(size == 1 || s->ghost_rebuilds == rebuilds, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "a move of at most 0.003 rebuilt the ghost layer (%" PetscInt_FMT " builds, %" PetscInt_FMT " before)", s->ghost_rebuilds, rebuilds);
  PetscCall(CheckAgainstBruteForce(ct, s, "after a tiny move (ghosts refreshed, not rebuilt)", NULL));
  counts[0] = counts[1] = 0;
  PetscCall(CheckPersistence(ct, s, oldkeys, nold, counts));
  PetscCallMPI(MPI_Allreduce(counts, gcounts, 2, MPIU_INT, MPI_SUM, comm));
  PetscCheck(gcounts[0] > 0, comm, PETSC_ERR_PLIB, "tiny move: no pair kept its impulse");
  PetscCall(PetscPrintf(comm, "tiny move: %" PetscInt_FMT " pairs kept their impulse, %" PetscInt_FMT " new\n", gcounts[0], gcounts[1]));
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
  const PetscInt  ndisks   = (PetscInt)(sizeof(pos) / sizeof(pos[0]));
  Reference expect[] = {
      {0, KERGS_CONTACT_DISK_DISK, 1, 0.1 - eps, {-1.0, 0.0}, 0, 0, 0, 0, 0},
      {4, KERGS_CONTACT_DISK_WALL, 0, 0.1 - eps, {0.0, 1.0}, 0, 0, 0, 0, 0},
      {7, KERGS_CONTACT_DISK_WALL, 1, 0.05, {1.0, 0.0}, 0, 0, 0, 0, 0},
  };
  PetscReal     x[2 * (sizeof(pos) / sizeof(pos[0]))], r[sizeof(pos) / sizeof(pos[0])];
  KergsScene    s;
  KergsContacts ct;
  Disks        g;

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
  PetscCheck(ct->n == 3 && ct->nglobal == 3 && ct->start == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "alert test: %" PetscInt_FMT " contacts, expected 3", ct->n);
  for (PetscInt k = 0; k < 3; k++) PetscCall(CheckContact(s, &ct->c[k], &expect[k], k));
  PetscCheck(ct->ncellx * ct->ncelly <= 4 * ndisks + 64, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "grid of %" PetscInt_FMT " x %" PetscInt_FMT " cells for %" PetscInt_FMT " disks", ct->ncellx, ct->ncelly, ndisks);
  PetscCall(PetscPrintf(
      PETSC_COMM_WORLD,
      "alert distance: gap alert - 1e-9 kept, alert + 1e-9 dropped; one-sided wall and segment ends honoured; far disk: %" PetscInt_FMT
      " cells\n",
      ct->ncellx * ct->ncelly));

  /* the same object again with a shrunk alert: the two contacts at gap 0.1 - eps drop out */
  s->alert = 0.1 - 2 * eps;
  PetscCall(KergsContactsDetect(ct, s));
  PetscCheck(ct->n == 1 && ct->c[0].a == 7, PETSC_COMM_SELF, PETSC_ERR_PLIB, "alert 0.1 - 2e-9: %" PetscInt_FMT " contacts, expected 1",
             ct->n);
  PetscCheck(ct->c[0].persistent, PETSC_COMM_SELF, PETSC_ERR_PLIB, "alert test: the kept wall contact is not persistent");
  PetscCall(KergsContactsDestroy(&ct));
  PetscCall(KergsSceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* Two disks on the same centre have no normal: detection must fail and name both grains. */
static PetscErrorCode TestCoincidentCentres(void)
{
  KergsScene     s;
  KergsContacts  ct;
  PetscErrorCode ierr;
  char          *message = NULL, *has1, *has2;
  const PetscReal x[6] = {5.0, 0.0, 0.0, 0.0, 0.0, 0.0}, r[3] = {0.5, 0.5, 0.5};

  PetscFunctionBeginUser;
  PetscCall(SceneCreate(PETSC_COMM_SELF, 0, 0.0, &s));
  PetscCall(SceneSetDisks(s, 3, x, r, NULL)); /* disk 0 apart, disks 1 and 2 at the origin; grains 1000, 1001, 1002 */
  PetscCall(KergsContactsCreate(PETSC_COMM_SELF, &ct));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KergsContactsDetect(ct, s);
  PetscCall(PetscPopErrorHandler());
  PetscCheck(ierr == PETSC_ERR_ARG_WRONG, PETSC_COMM_SELF, PETSC_ERR_PLIB, "coincident centres: error %d, expected PETSC_ERR_ARG_WRONG",
             (int)ierr);
  PetscCall(PetscErrorMessage(ierr, NULL, &message));
  PetscCall(PetscStrstr(message, "1001", &has1));
  PetscCall(PetscStrstr(message, "1002", &has2));
  PetscCheck(has1 && has2, PETSC_COMM_SELF, PETSC_ERR_PLIB, "coincident centres: message \"%s\" does not name grains 1001 and 1002",
             message);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "coincident centres: error names both grains (%s)\n", message));
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
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "test_detect: all checks passed\n"));
  PetscCall(PetscFinalize());
  return 0;
}
