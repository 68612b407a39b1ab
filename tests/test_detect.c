static const char help[] = "Tests of contact detection (src/detect.c): the cell-list search against a brute-force O(N^2)\n"
                           "search on a polydisperse packing with walls, ownership over ranks, persistence of impulses,\n"
                           "the alert distance, one-sided walls and segment ends, coincident centres, and a timing.\n";

/* The test builds its scenes by hand (the scene component is someone else's): only the fields
   detection reads are set. Every rank builds the same replicated scene and owns a contiguous block of
   disks, as PetscSplitOwnership would give. */
#include <kergs/detect.h>

#define TOL 1e-12

/* A contact as the brute-force search sees it. */
typedef struct {
  PetscInt  a, kind, b;
  PetscReal gap, n[KERGS_DIM];
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

static PetscErrorCode SceneCreate(MPI_Comm comm, PetscInt ndisks, PetscInt nwalls, PetscReal alert, KergsScene *scene)
{
  KergsScene s;
  PetscInt   nlocal = PETSC_DECIDE, n = ndisks;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(1, &s));
  s->comm = comm;
  PetscCall(PetscStrcpy(s->name, "test_detect"));
  s->ndisks = ndisks;
  PetscCall(PetscCalloc4(ndisks, &s->id, KERGS_DIM * ndisks, &s->x, ndisks, &s->radius, ndisks, &s->material));
  for (PetscInt i = 0; i < ndisks; i++) {
    s->id[i]       = 1000 + i;
    s->material[i] = i % 2;
  }
  PetscCall(PetscSplitOwnership(comm, &nlocal, &n));
  PetscCallMPI(MPI_Scan(&nlocal, &s->dend, 1, MPIU_INT, MPI_SUM, comm));
  s->dstart = s->dend - nlocal;
  s->nwalls = nwalls;
  PetscCall(PetscCalloc1(nwalls, &s->walls));
  s->nmaterials = 2;
  PetscCall(PetscMalloc1(4, &s->mu));
  s->mu[0] = 0.3;
  s->mu[1] = s->mu[2] = 0.5;
  s->mu[3]            = 0.1;
  s->frictional       = PETSC_TRUE;
  s->alert            = alert;
  *scene              = s;
  PetscFunctionReturn(0);
}

static PetscErrorCode SceneDestroy(KergsScene *scene)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree4((*scene)->id, (*scene)->x, (*scene)->radius, (*scene)->material));
  PetscCall(PetscFree((*scene)->walls));
  PetscCall(PetscFree((*scene)->mu));
  PetscCall(PetscFree(*scene));
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
   tilted line across the inside so that disks lie on both sides of some walls and beyond segment ends. */
static PetscErrorCode RandomPackingWithWalls(MPI_Comm comm, PetscInt ndisks, unsigned long long seed, KergsScene *scene)
{
  const PetscReal rmin = 0.1;
  PetscReal       area = 0.0, L;
  KergsScene      s;

  PetscFunctionBeginUser;
  PetscCall(SceneCreate(comm, ndisks, 6, 0.2 * rmin, &s));
  for (PetscInt i = 0; i < ndisks; i++) {
    const PetscReal u = Uniform(&seed);
    s->radius[i]      = rmin * (1.0 + 9.0 * u * u * u);
    area += PETSC_PI * s->radius[i] * s->radius[i];
  }
  L = PetscSqrtReal(area / 0.75);
  for (PetscInt i = 0; i < KERGS_DIM * ndisks; i++) s->x[i] = L * Uniform(&seed);
  PetscCall(SetWall(s, 0, PETSC_TRUE, 0, 0, 1, 0, 0));                          /* bottom line, normal +y */
  PetscCall(SetWall(s, 1, PETSC_FALSE, 0, L, 0, 0, 1));                         /* left segment, normal +x */
  PetscCall(SetWall(s, 2, PETSC_FALSE, 0.8 * L, L, 0.2 * L, L, 0));             /* part of the top, normal -y */
  PetscCall(SetWall(s, 3, PETSC_TRUE, L, 0, L, 1, 1));                          /* right line, normal -x */
  PetscCall(SetWall(s, 4, PETSC_FALSE, 0.3 * L, 0.3 * L, 0.7 * L, 0.5 * L, 1)); /* tilted segment inside */
  PetscCall(SetWall(s, 5, PETSC_TRUE, 0.0, 0.2 * L, 1.0, 0.2 * L - 0.25, 0));   /* tilted line inside */
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

/* Every potential contact of the scene over all disks, by the O(N^2) definition, in (a, kind, b) order.
   The wall test is written independently of detect.c: signed distance by the cross product
   (b - a) x (x - a) / |b - a|, and the segment test on the parameter of the projection in [0, 1]. */
static PetscErrorCode BruteForce(KergsScene s, Reference **ref, PetscInt *nref)
{
  PetscInt   n = 0, cap = 16;
  Reference *r;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(cap, &r));
  for (PetscInt i = 0; i < s->ndisks; i++) {
    const PetscReal *xi = &s->x[KERGS_DIM * i];
    for (PetscInt j = i + 1; j < s->ndisks; j++) {
      const PetscReal *xj   = &s->x[KERGS_DIM * j];
      const PetscReal  dist = PetscSqrtReal((xi[0] - xj[0]) * (xi[0] - xj[0]) + (xi[1] - xj[1]) * (xi[1] - xj[1]));
      const PetscReal  gap  = dist - s->radius[i] - s->radius[j];

      if (gap >= s->alert) continue;
      if (n == cap) PetscCall(PetscRealloc((size_t)(cap *= 2) * sizeof(Reference), &r));
      r[n].a    = i;
      r[n].kind = KERGS_CONTACT_DISK_DISK;
      r[n].b    = j;
      r[n].gap  = gap;
      r[n].n[0] = (xi[0] - xj[0]) / dist;
      r[n].n[1] = (xi[1] - xj[1]) / dist;
      n++;
    }
    for (PetscInt w = 0; w < s->nwalls; w++) {
      const KergsWall *wall = &s->walls[w];
      const PetscReal  ux = wall->b[0] - wall->a[0], uy = wall->b[1] - wall->a[1], len = PetscSqrtReal(ux * ux + uy * uy);
      const PetscReal  px = xi[0] - wall->a[0], py = xi[1] - wall->a[1];
      const PetscReal  d = (ux * py - uy * px) / len, lambda = (ux * px + uy * py) / (len * len);

      if (!(d > 0.0) || d - s->radius[i] >= s->alert) continue;
      if (!wall->infinite && (lambda < 0.0 || lambda > 1.0)) continue;
      if (n == cap) PetscCall(PetscRealloc((size_t)(cap *= 2) * sizeof(Reference), &r));
      r[n].a    = i;
      r[n].kind = KERGS_CONTACT_DISK_WALL;
      r[n].b    = w;
      r[n].gap  = d - s->radius[i];
      r[n].n[0] = -uy / len;
      r[n].n[1] = ux / len;
      n++;
    }
  }
  *ref  = r;
  *nref = n;
  PetscFunctionReturn(0);
}

/* Geometry and bookkeeping of one contact against its reference. */
static PetscErrorCode CheckContact(KergsScene s, const KergsContact *c, const Reference *ref, PetscInt k)
{
  const PetscReal nnorm = PetscSqrtReal(c->n[0] * c->n[0] + c->n[1] * c->n[1]);
  const PetscInt  mb    = c->kind == KERGS_CONTACT_DISK_DISK ? s->material[c->b] : s->walls[c->b].material;
  PetscReal       along;

  PetscFunctionBeginUser;
  PetscCheck(c->a == ref->a && (PetscInt)c->kind == ref->kind && c->b == ref->b, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT " is (%" PetscInt_FMT ", %d, %" PetscInt_FMT "), brute force says (%" PetscInt_FMT ", %" PetscInt_FMT
             ", %" PetscInt_FMT ")",
             k, c->a, (int)c->kind, c->b, ref->a, ref->kind, ref->b);
  PetscCheck(PetscAbsReal(c->gap - ref->gap) <= TOL, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT ": gap %.17g, brute force %.17g", k, (double)c->gap, (double)ref->gap);
  PetscCheck(PetscAbsReal(nnorm - 1.0) <= TOL, PETSC_COMM_SELF, PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": |n| = %.17g", k, (double)nnorm);
  PetscCheck(PetscAbsReal(c->n[0] - ref->n[0]) <= TOL && PetscAbsReal(c->n[1] - ref->n[1]) <= TOL, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT ": n = (%g, %g), brute force (%g, %g)", k, (double)c->n[0], (double)c->n[1], (double)ref->n[0],
             (double)ref->n[1]);
  /* n points from b towards a: for a disk pair along x_a - x_b, for a wall towards the centre's side */
  if (c->kind == KERGS_CONTACT_DISK_DISK)
    along = c->n[0] * (s->x[2 * c->a] - s->x[2 * c->b]) + c->n[1] * (s->x[2 * c->a + 1] - s->x[2 * c->b + 1]);
  else
    along = c->n[0] * (s->x[2 * c->a] - s->walls[c->b].a[0]) + c->n[1] * (s->x[2 * c->a + 1] - s->walls[c->b].a[1]);
  PetscCheck(along > 0.0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": normal does not point from b to a", k);
  PetscCheck(c->t[0] == -c->n[1] && c->t[1] == c->n[0], PETSC_COMM_SELF, PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": t is not (-n_y, n_x)",
             k);
  PetscCheck(c->ra == s->radius[c->a] && c->rb == (c->kind == KERGS_CONTACT_DISK_DISK ? s->radius[c->b] : 0.0), PETSC_COMM_SELF,
             PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": wrong radii", k);
  PetscCheck(c->mu == s->mu[s->material[c->a] * s->nmaterials + mb], PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "contact %" PetscInt_FMT ": wrong friction coefficient", k);
  for (PetscInt d = 0; d < KERGS_MAXCOMP; d++)
    PetscCheck(c->v[d] == 0.0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "contact %" PetscInt_FMT ": v not zeroed", k);
  PetscFunctionReturn(0);
}

/* The contacts of this rank are exactly the brute-force contacts of its own disks, in order; gathered over
   the ranks, the keys are exactly the brute-force list (each contact found once); nglobal and start agree. */
static PetscErrorCode CheckAgainstBruteForce(KergsContacts ct, KergsScene s, const char label[])
{
  Reference  *ref  = NULL;
  PetscInt    nref = 0, first = 0, nall, *keys, *allkeys;
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
             "%s: %" PetscInt_FMT " local contacts, not the brute-force count of the owned disks", label, ct->n);
  for (PetscInt k = 0; k < ct->n; k++) {
    PetscCheck(s->dstart <= ct->c[k].a && ct->c[k].a < s->dend, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: contact %" PetscInt_FMT " of disk %" PetscInt_FMT " not owned here", label, k, ct->c[k].a);
    if (k > 0)
      PetscCheck(CompareKeys(ct->c[k - 1].a, ct->c[k - 1].kind, ct->c[k - 1].b, ct->c[k].a, ct->c[k].kind, ct->c[k].b) < 0, PETSC_COMM_SELF,
                 PETSC_ERR_PLIB, "%s: contacts %" PetscInt_FMT " and %" PetscInt_FMT " out of (a, kind, b) order", label, k - 1, k);
    PetscCall(CheckContact(s, &ct->c[k], &ref[first + k], k));
  }
  /* gather every rank's keys: the union must be the brute-force list with no repeats */
  PetscCall(PetscMalloc1(3 * ct->n + 1, &keys));
  for (PetscInt k = 0; k < ct->n; k++) {
    keys[3 * k]     = ct->c[k].a;
    keys[3 * k + 1] = ct->c[k].kind;
    keys[3 * k + 2] = ct->c[k].b;
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
  for (PetscInt k = 0; k < nall; k++)
    PetscCheck(CompareKeys(allkeys[3 * k], allkeys[3 * k + 1], allkeys[3 * k + 2], ref[k].a, ref[k].kind, ref[k].b) == 0, PETSC_COMM_SELF,
               PETSC_ERR_PLIB, "%s: gathered contact %" PetscInt_FMT " differs from brute force", label, k);
  PetscCall(PetscPrintf(s->comm,
                        "%s: %" PetscInt_FMT " contacts match brute force (pairs, gaps and normals to %g) on %d rank(s), each found once\n",
                        label, nref, (double)TOL, (int)size));
  PetscCall(PetscFree(allkeys));
  PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree(keys));
  PetscCall(PetscFree(ref));
  PetscFunctionReturn(0);
}

/* A known impulse per pair, to see it carried over. */
static PetscReal PairImpulse(PetscInt a, PetscInt kind, PetscInt b, PetscInt comp)
{
  return (comp == 0 ? 1.0 : -0.5) * (1.0 + (PetscReal)a + 1e-3 * (PetscReal)b + 0.25 * (PetscReal)kind);
}

static PetscErrorCode TestPackingAndPersistence(MPI_Comm comm)
{
  const PetscInt     ndisks = 3000;
  KergsScene         s      = NULL;
  KergsContacts      ct     = NULL;
  PetscInt           nold, *oldkeys, counts[2] = {0, 0}, gcounts[2], nwall = 0;
  unsigned long long seed = 12345;

  PetscFunctionBeginUser;
  PetscCall(RandomPackingWithWalls(comm, ndisks, 2024, &s));
  PetscCall(KergsContactsCreate(comm, &ct));
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(CheckAgainstBruteForce(ct, s, "polydisperse packing with walls"));
  for (PetscInt k = 0; k < ct->n; k++) {
    PetscCheck(!ct->c[k].persistent && ct->c[k].r[0] == 0.0 && ct->c[k].r[1] == 0.0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "first detection: contact %" PetscInt_FMT " not fresh", k);
    nwall += ct->c[k].kind == KERGS_CONTACT_DISK_WALL;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nwall, 1, MPIU_INT, MPI_SUM, comm));
  PetscCheck(nwall >= 20, comm, PETSC_ERR_PLIB, "only %" PetscInt_FMT " disk-wall contacts: the walls are not exercised", nwall);
  PetscCall(
      PetscPrintf(comm, "first detection: every contact fresh (r = 0, not persistent), %" PetscInt_FMT " disk-wall contacts\n", nwall));

  /* impulses as a solver would leave them, and velocities that must not survive */
  nold = ct->n;
  PetscCall(PetscMalloc1(3 * nold + 1, &oldkeys));
  for (PetscInt k = 0; k < ct->n; k++) {
    KergsContact *c = &ct->c[k];
    for (PetscInt d = 0; d < KERGS_MAXCOMP; d++) {
      c->r[d] = PairImpulse(c->a, c->kind, c->b, d);
      c->v[d] = 99.0;
    }
    oldkeys[3 * k]     = c->a;
    oldkeys[3 * k + 1] = c->kind;
    oldkeys[3 * k + 2] = c->b;
  }
  /* move every disk by up to 0.03 (radii 0.1 .. 1): some pairs part, others meet */
  for (PetscInt i = 0; i < KERGS_DIM * s->ndisks; i++) s->x[i] += 0.06 * (Uniform(&seed) - 0.5);
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(CheckAgainstBruteForce(ct, s, "after a small move"));
  for (PetscInt k = 0, j = 0; k < ct->n; k++) {
    const KergsContact *c = &ct->c[k];
    PetscBool           was;

    while (j < nold && CompareKeys(oldkeys[3 * j], oldkeys[3 * j + 1], oldkeys[3 * j + 2], c->a, c->kind, c->b) < 0) j++;
    was = (PetscBool)(j < nold && CompareKeys(oldkeys[3 * j], oldkeys[3 * j + 1], oldkeys[3 * j + 2], c->a, c->kind, c->b) == 0);
    PetscCheck(c->persistent == was, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "contact (%" PetscInt_FMT ", %d, %" PetscInt_FMT "): persistent flag %d, expected %d", c->a, (int)c->kind, c->b,
               (int)c->persistent, (int)was);
    for (PetscInt d = 0; d < KERGS_MAXCOMP; d++) {
      const PetscReal expect = was ? PairImpulse(c->a, c->kind, c->b, d) : 0.0;
      PetscCheck(c->r[d] == expect, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "contact (%" PetscInt_FMT ", %d, %" PetscInt_FMT "): r[%" PetscInt_FMT "] = %g, expected %g", c->a, (int)c->kind, c->b, d,
                 (double)c->r[d], (double)expect);
    }
    counts[was ? 0 : 1]++;
  }
  PetscCallMPI(MPI_Allreduce(counts, gcounts, 2, MPIU_INT, MPI_SUM, comm));
  PetscCheck(gcounts[0] > 0 && gcounts[1] > 0 && gcounts[0] + gcounts[1] == ct->nglobal, comm, PETSC_ERR_PLIB,
             "persistence not exercised: %" PetscInt_FMT " kept, %" PetscInt_FMT " new", gcounts[0], gcounts[1]);
  PetscCall(PetscPrintf(
      comm, "persistence: %" PetscInt_FMT " pairs kept their impulse, %" PetscInt_FMT " new pairs start from zero, flags right\n",
      gcounts[0], gcounts[1]));
  PetscCall(PetscFree(oldkeys));
  PetscCall(KergsContactsDestroy(&ct));
  PetscCall(SceneDestroy(&s));
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
  const Reference expect[] = {
      {0, KERGS_CONTACT_DISK_DISK, 1, 0.1 - eps, {-1.0, 0.0}},
      {4, KERGS_CONTACT_DISK_WALL, 0, 0.1 - eps, {0.0, 1.0}},
      {7, KERGS_CONTACT_DISK_WALL, 1, 0.05, {1.0, 0.0}},
  };
  KergsScene    s;
  KergsContacts ct;

  PetscFunctionBeginUser;
  PetscCall(SceneCreate(PETSC_COMM_SELF, ndisks, 2, alert, &s));
  for (PetscInt i = 0; i < ndisks; i++) {
    s->x[2 * i]     = pos[i][0];
    s->x[2 * i + 1] = pos[i][1];
    s->radius[i]    = 1.0;
  }
  PetscCall(SetWall(s, 0, PETSC_TRUE, 0, 0, 1, 0, 0));       /* bottom line, normal +y */
  PetscCall(SetWall(s, 1, PETSC_FALSE, 200, 10, 200, 0, 1)); /* segment, normal +x */
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
  PetscCall(SceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* Two disks on the same centre have no normal: detection must fail and name both grains. */
static PetscErrorCode TestCoincidentCentres(void)
{
  KergsScene     s;
  KergsContacts  ct;
  PetscErrorCode ierr;
  char          *message = NULL, *has1, *has2;

  PetscFunctionBeginUser;
  PetscCall(SceneCreate(PETSC_COMM_SELF, 3, 0, 0.0, &s));
  for (PetscInt i = 0; i < 3; i++) s->radius[i] = 0.5;
  s->x[0] = 5.0; /* disk 0 apart, disks 1 and 2 at the origin */
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
  PetscCall(SceneDestroy(&s));
  PetscFunctionReturn(0);
}

/* A dense packing of 50,000 disks in random order (the worst case for memory access):
   time one detection and a second one (with persistence), and print the cost per grain. */
static PetscErrorCode TimeDetection(MPI_Comm comm)
{
  const PetscInt     nx = 250, ny = 200, ndisks = nx * ny;
  KergsScene         s;
  KergsContacts      ct;
  PetscInt          *perm;
  unsigned long long seed = 7;
  PetscLogDouble     t0, t1, t2, tmax[2], tloc[2];

  PetscFunctionBeginUser;
  PetscCall(SceneCreate(comm, ndisks, 4, 0.05, &s));
  /* jittered triangular lattice of spacing 2 (six neighbours each), radii 0.97 .. 1.03, stored in a random
     permutation; gaps between neighbours spread over [-0.16, 0.16] around the alert distance 0.05 */
  PetscCall(PetscMalloc1(ndisks, &perm));
  for (PetscInt i = 0; i < ndisks; i++) perm[i] = i;
  for (PetscInt i = ndisks - 1; i > 0; i--) {
    PetscInt j = (PetscInt)(Uniform(&seed) * (PetscReal)(i + 1)), tmp = perm[i];
    perm[i] = perm[j];
    perm[j] = tmp;
  }
  for (PetscInt i = 0; i < ndisks; i++) {
    const PetscInt k = perm[i], row = i / nx, col = i % nx;
    s->x[2 * k]     = 2.0 * (PetscReal)col + (PetscReal)(row % 2) + 1.0 + 0.1 * (Uniform(&seed) - 0.5);
    s->x[2 * k + 1] = PetscSqrtReal(3.0) * (PetscReal)row + 1.0 + 0.1 * (Uniform(&seed) - 0.5);
    s->radius[k]    = 0.97 + 0.06 * Uniform(&seed);
  }
  PetscCall(SetWall(s, 0, PETSC_TRUE, 0, 0, 1, 0, 0));
  PetscCall(SetWall(s, 1, PETSC_TRUE, 0, 1, 0, 0, 0));
  PetscCall(SetWall(s, 2, PETSC_TRUE, 2.0 * nx + 1.0, 0, 2.0 * nx + 1.0, 1, 0));
  PetscCall(SetWall(s, 3, PETSC_TRUE, 1, PetscSqrtReal(3.0) * ny, 0, PetscSqrtReal(3.0) * ny, 0));
  PetscCall(KergsContactsCreate(comm, &ct));
  PetscCallMPI(MPI_Barrier(comm));
  PetscCall(PetscTime(&t0));
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(PetscTime(&t1));
  PetscCall(KergsContactsDetect(ct, s));
  PetscCall(PetscTime(&t2));
  tloc[0] = t1 - t0;
  tloc[1] = t2 - t1;
  PetscCallMPI(MPI_Allreduce(tloc, tmax, 2, MPI_DOUBLE, MPI_MAX, comm));
  PetscCheck(ct->nglobal > 2 * ndisks, comm, PETSC_ERR_PLIB, "timing packing: only %" PetscInt_FMT " contacts", ct->nglobal);
  PetscCall(PetscPrintf(comm,
                        "timing: %" PetscInt_FMT " disks, %" PetscInt_FMT
                        " contacts, first detection %.0f ns per grain, second (persistent) %.0f ns per grain (slowest rank)\n",
                        ndisks, ct->nglobal, 1e9 * tmax[0] / ndisks, 1e9 * tmax[1] / ndisks));
  PetscCall(PetscFree(perm));
  PetscCall(KergsContactsDestroy(&ct));
  PetscCall(SceneDestroy(&s));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCall(TestPackingAndPersistence(PETSC_COMM_WORLD));
  PetscCall(TestAlertAndWalls());
  PetscCall(TestCoincidentCentres());
  PetscCall(TimeDetection(PETSC_COMM_WORLD));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "test_detect: all checks passed\n"));
  PetscCall(PetscFinalize());
  return 0;
}
