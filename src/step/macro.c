/* kergs stepper: the macroscopic response of the step just taken, as a biaxial test reads it (docs/results.md,
   "Macroscopic response"): the Love-Weber stress from the contact forces and the stress from the wall forces, the
   principal stresses and q/p, the strains and the solid fraction from the walls' box, the coordination number with
   and without rattlers, the Rothenburg-Bathurst anisotropies and the fraction of sliding contacts. Post-processing of
   the contacts' impulses after the solve: nothing here feeds back into the step (the rest rule of -stop_at_rest_stress
   reads the Love-Weber stress minus the boundary's, st->inertia_stress, to decide whether to stop). Every figure is
   global. */
#include <kergs/private/stepperimpl.h>

/* The four walls of an axis-aligned box, by the side they hold (-1: none), and the rectangle they span. */
typedef struct {
  PetscBool found;
  PetscInt  left, right, bottom, top;
  PetscReal x0, x1, y0, y1;
} MacroBox;

/* The sums over this rank's owned contacts and disks, reduced in one call. Stress: sum f_i l_j; fabric: sum n_i n_j;
   normal and tangential force tensors: sum f_n n_i n_j and the symmetric part of sum f_t t_i n_j (disk-disk). */
enum {
  M_SXX,
  M_SXY,
  M_SYX,
  M_SYY,
  M_WALL, /* normal force on the box's walls: left, right, bottom, top */
  M_NDD = M_WALL + 4,
  M_NDW,
  M_NSLIDE,
  M_FXX,
  M_FXY,
  M_FYY,
  M_NXX,
  M_NXY,
  M_NYY,
  M_TXX,
  M_TXY,
  M_TYY,
  M_FN,
  M_AREA,
  M_BXX, /* the boundary's stress: minus the moment of every wall traction about the box's centre, friction included */
  M_BXY,
  M_BYX,
  M_BYY,
  M_NSUMS
};

/* A box is exactly four walls whose normals point along +x, -x, +y and -y into a rectangle of positive size. */
static PetscErrorCode FindBox(PetscInt nwalls, const KergsWall walls[], MacroBox *box)
{
  PetscInt *side[4] = {&box->left, &box->right, &box->bottom, &box->top};

  PetscFunctionBeginUser;
  box->left = box->right = box->bottom = box->top = -1;
  box->x0 = box->x1 = box->y0 = box->y1 = 0; /* read by AddTraction even without a box */
  box->found                            = PETSC_FALSE;
  if (nwalls != 4) PetscFunctionReturn(0);
  for (PetscInt w = 0; w < nwalls; w++) {
    const PetscReal dx = walls[w].b[0] - walls[w].a[0], dy = walls[w].b[1] - walls[w].a[1];
    PetscInt        s = -1;
    if (dy == 0 && dx != 0) s = dx > 0 ? 2 : 3; /* normal (-dy, dx): +y for a bottom wall drawn left to right */
    if (dx == 0 && dy != 0) s = dy < 0 ? 0 : 1; /* +x for a left wall drawn top to bottom */
    if (s < 0 || *side[s] >= 0) PetscFunctionReturn(0);
    *side[s] = w;
  }
  box->x0    = walls[box->left].a[0];
  box->x1    = walls[box->right].a[0];
  box->y0    = walls[box->bottom].a[1];
  box->y1    = walls[box->top].a[1];
  box->found = (PetscBool)(box->x1 > box->x0 && box->y1 > box->y0);
  PetscFunctionReturn(0);
}

/* Whether the walls make the box the macroscopic response is measured in */
PetscErrorCode KergsStepperHasBox(KergsStepper st, PetscBool *found)
{
  const KergsWall *walls;
  PetscInt         nwalls;
  MacroBox         box;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  PetscCall(FindBox(nwalls, walls, &box));
  *found = box.found;
  PetscFunctionReturn(0);
}

/* Compression positive, relative to the box at the start of the run (the walls' displacements, kept by checkpoints):
   axial eps_a = -dH/H0 (vertical), lateral eps_l = -dW/W0, volumetric eps_v = eps_a + eps_l (DESIGN section 9). */
static void BoxStrains(const KergsWall walls[], const MacroBox *box, PetscReal eps[3])
{
  const PetscReal W = box->x1 - box->x0, H = box->y1 - box->y0;
  const PetscReal W0 = W - (walls[box->right].disp[0] - walls[box->left].disp[0]);
  const PetscReal H0 = H - (walls[box->top].disp[1] - walls[box->bottom].disp[1]);

  eps[0] = -(H - H0) / H0;
  eps[1] = -(W - W0) / W0;
  eps[2] = eps[0] + eps[1];
}

/* The box side a wall holds (0 left, 1 right, 2 bottom, 3 top; -1: not a box wall) */
static PetscInt BoxSide(const MacroBox *box, PetscInt w)
{
  if (!box->found) return -1;
  return w == box->left ? 0 : w == box->right ? 1 : w == box->bottom ? 2 : w == box->top ? 3 : -1;
}

/* One force-carrying contact's share of the sums. f = r / dt on disk a; the branch vector l runs from b towards a: from
   centre to centre for two disks, from the contact point to the centre (r_a n) for a wall, so that f (x) l is positive
   in compression. */
static void AddContact(const KergsContact *c, const PetscReal l[], PetscReal dt, PetscReal s[])
{
  const PetscReal fn = c->r[0] / dt, ft = c->r[1] / dt;
  const PetscReal f[2] = {fn * c->n[0] + ft * c->t[0], fn * c->n[1] + ft * c->t[1]};

  s[M_SXX] += f[0] * l[0];
  s[M_SXY] += f[0] * l[1];
  s[M_SYX] += f[1] * l[0];
  s[M_SYY] += f[1] * l[1];
  if (c->mu > 0 && PetscAbsReal(c->r[1]) >= c->mu * c->r[0] * (1 - 1e-6)) s[M_NSLIDE] += 1;
  if (c->kind != KERGS_CONTACT_DISK_DISK) return;
  s[M_NDD] += 1;
  s[M_FXX] += c->n[0] * c->n[0];
  s[M_FXY] += c->n[0] * c->n[1];
  s[M_FYY] += c->n[1] * c->n[1];
  s[M_NXX] += fn * c->n[0] * c->n[0];
  s[M_NXY] += fn * c->n[0] * c->n[1];
  s[M_NYY] += fn * c->n[1] * c->n[1];
  s[M_TXX] += ft * c->t[0] * c->n[0];
  s[M_TXY] += ft * 0.5 * (c->t[0] * c->n[1] + c->t[1] * c->n[0]);
  s[M_TYY] += ft * c->t[1] * c->n[1];
  s[M_FN] += fn;
}

/* A wall's traction on disk a, f = r / dt at the contact point x_a - r_a n, into the boundary's stress
   -sum f (x) (point - centre): in static equilibrium without body forces it equals the Love-Weber stress (each
   disk's forces balance), and their difference is sum m dv/dt (x) x over the disks, the stress of their inertia. */
static void AddTraction(const KergsContact *c, const PetscReal xa[], const MacroBox *box, PetscReal dt, PetscReal s[])
{
  const PetscReal fn = c->r[0] / dt, ft = c->r[1] / dt;
  const PetscReal f[2]  = {fn * c->n[0] + ft * c->t[0], fn * c->n[1] + ft * c->t[1]};
  const PetscReal pt[2] = {xa[0] - c->ra * c->n[0] - 0.5 * (box->x0 + box->x1), xa[1] - c->ra * c->n[1] - 0.5 * (box->y0 + box->y1)};

  s[M_BXX] -= f[0] * pt[0];
  s[M_BXY] -= f[0] * pt[1];
  s[M_BYX] -= f[1] * pt[0];
  s[M_BYY] -= f[1] * pt[1];
}

static void SumContacts(const KergsDisks *D, PetscInt n, const KergsContact c[], const MacroBox *box, PetscReal dt, PetscReal s[])
{
  for (PetscInt k = 0; k < n; k++) {
    const PetscReal *xa = &D->x[KERGS_DIM * c[k].a];
    PetscReal        l[KERGS_DIM];
    if (!(c[k].r[0] > 0)) continue; /* force-carrying contacts only */
    if (c[k].kind == KERGS_CONTACT_DISK_DISK) {
      for (PetscInt d = 0; d < KERGS_DIM; d++) l[d] = xa[d] - D->x[KERGS_DIM * c[k].b + d];
    } else {
      const PetscInt side = BoxSide(box, c[k].b);
      for (PetscInt d = 0; d < KERGS_DIM; d++) l[d] = c[k].ra * c[k].n[d];
      s[M_NDW] += 1;
      if (side >= 0) s[M_WALL + side] += c[k].r[0] / dt;
      AddTraction(&c[k], xa, box, dt, s);
    }
    AddContact(&c[k], l, dt, s);
  }
  for (PetscInt i = 0; i < D->nowned; i++) s[M_AREA] += PETSC_PI * D->radius[i] * D->radius[i];
}

/* Eigenvalues s1 >= s2 of the symmetric 2x2 tensor [xx xy; xy yy] */
static void Principal(PetscReal xx, PetscReal yy, PetscReal xy, PetscReal *s1, PetscReal *s2)
{
  const PetscReal mean = 0.5 * (xx + yy), radius = PetscSqrtReal(0.25 * (xx - yy) * (xx - yy) + xy * xy);

  *s1 = mean + radius;
  *s2 = mean - radius;
}

/* Rothenburg-Bathurst anisotropies from the fabric F = <n n>, chi_n = sum f_n n n / sum f_n and chi_t = sum f_t t n /
   sum f_n (symmetric part), with principal values (1 >= 2): a_c = 2 (F1 - F2) / (F1 + F2),
   a_c + a_n = 2 (n1 - n2) / (n1 + n2) of chi_n, a_c + a_n + a_t = 2 (t1 - t2) / (n1 + n2) of chi_n + chi_t
   (docs/results.md; then q/p ~ (a_c + a_n + a_t) / 2). Zero without force-carrying disk-disk contacts. */
static void Anisotropies(const PetscReal s[], PetscReal a[3])
{
  PetscReal f1, f2, n1, n2, t1, t2;

  a[0] = a[1] = a[2] = 0;
  if (!(s[M_NDD] > 0) || !(s[M_FN] > 0)) return;
  Principal(s[M_FXX], s[M_FYY], s[M_FXY], &f1, &f2);
  Principal(s[M_NXX], s[M_NYY], s[M_NXY], &n1, &n2);
  Principal(s[M_NXX] + s[M_TXX], s[M_NYY] + s[M_TYY], s[M_NXY] + s[M_TXY], &t1, &t2);
  a[0] = 2 * (f1 - f2) / (f1 + f2);
  a[1] = 2 * (n1 - n2) / (n1 + n2) - a[0];
  a[2] = 2 * (t1 - t2) / (n1 + n2) - a[0] - a[1];
}

/* The star forest from each ghost (leaf) to its owner's disk (root), to sum per-grain counts over ranks. */
static PetscErrorCode GhostSF(MPI_Comm comm, const KergsDisks *D, PetscSF *sf)
{
  PetscMPIInt  size;
  PetscInt    *starts, *ilocal, nghosts = D->nlocal - D->nowned;
  PetscSFNode *iremote;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscMalloc3(size, &starts, nghosts, &ilocal, nghosts, &iremote));
  PetscCallMPI(MPI_Allgather(&D->dstart, 1, MPIU_INT, starts, 1, MPIU_INT, comm));
  for (PetscInt g = 0; g < nghosts; g++) {
    ilocal[g]        = D->nowned + g;
    iremote[g].rank  = D->ghost_owner[g];
    iremote[g].index = D->gidx[D->nowned + g] - starts[D->ghost_owner[g]];
  }
  PetscCall(PetscSFCreate(comm, sf));
  PetscCall(PetscSFSetGraph(*sf, D->nowned, nghosts, ilocal, PETSC_COPY_VALUES, iremote, PETSC_COPY_VALUES));
  PetscCall(PetscFree3(starts, ilocal, iremote));
  PetscFunctionReturn(0);
}

/* Force-carrying contacts per owned grain, leaving out those with a rattler at either end (walls never rattle):
   counts[0, nowned) summed over the ranks; counts[nowned, nlocal) is scratch. */
static PetscErrorCode CountContacts(PetscSF sf, const KergsDisks *D, PetscInt n, const KergsContact c[], const PetscInt rattler[],
                                    PetscInt counts[], PetscInt owned[])
{
  PetscFunctionBeginUser;
  PetscCall(PetscArrayzero(counts, D->nlocal));
  for (PetscInt k = 0; k < n; k++) {
    const PetscBool dd = (PetscBool)(c[k].kind == KERGS_CONTACT_DISK_DISK);
    if (!(c[k].r[0] > 0) || rattler[c[k].a] || (dd && rattler[c[k].b])) continue;
    counts[c[k].a]++;
    if (dd) counts[c[k].b]++;
  }
  PetscCall(PetscArraycpy(owned, counts, D->nowned));
  PetscCall(PetscSFReduceBegin(sf, MPIU_INT, counts, owned, MPI_SUM));
  PetscCall(PetscSFReduceEnd(sf, MPIU_INT, counts, owned, MPI_SUM));
  PetscFunctionReturn(0);
}

/* Rattlers: grains with fewer than 2 force-carrying contacts, removed with their contacts round after round until no
   grain is left with fewer than 2 (DESIGN section 9). Global: the number of rattlers and the sum of the other grains'
   counts among themselves and the walls. */
static PetscErrorCode FindRattlers(MPI_Comm comm, const KergsDisks *D, PetscInt n, const KergsContact c[], PetscInt *nrattlers,
                                   PetscInt *nends)
{
  PetscSF   sf;
  PetscInt *rattler, *counts, *owned, found[2] = {1, 0};

  PetscFunctionBeginUser;
  PetscCall(GhostSF(comm, D, &sf));
  PetscCall(PetscCalloc3(D->nlocal, &rattler, D->nlocal, &counts, D->nowned, &owned));
  while (found[0] > 0) {
    PetscInt mine[2] = {0, 0};
    PetscCall(CountContacts(sf, D, n, c, rattler, counts, owned));
    for (PetscInt i = 0; i < D->nowned; i++) {
      if (!rattler[i] && owned[i] < 2)
        rattler[i] = mine[0] = 1;
      else if (!rattler[i])
        mine[1] += owned[i];
    }
    PetscCall(MPIU_Allreduce(mine, found, 2, MPIU_INT, MPI_SUM, comm));
    PetscCall(PetscArraycpy(owned, rattler, D->nowned)); /* the ghosts learn their owners' verdict */
    PetscCall(PetscSFBcastBegin(sf, MPIU_INT, owned, rattler, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_INT, owned, rattler, MPI_REPLACE));
  }
  *nends     = found[1];
  *nrattlers = 0;
  for (PetscInt i = 0; i < D->nowned; i++) *nrattlers += rattler[i];
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, nrattlers, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(PetscFree3(rattler, counts, owned));
  PetscCall(PetscSFDestroy(&sf));
  PetscFunctionReturn(0);
}

/* The Love-Weber tensor sxx, syy, sxy over the box's area (zero without a box), or the boundary's from the sums at
   first (M_SXX or M_BXX) */
static void StressOverBox(const MacroBox *box, const PetscReal s[], PetscInt first, PetscReal sigma[3])
{
  const PetscReal A = box->found ? (box->x1 - box->x0) * (box->y1 - box->y0) : 0;

  sigma[0] = A > 0 ? s[first] / A : 0; /* xx, xy, yx, yy from first on */
  sigma[1] = A > 0 ? s[first + 3] / A : 0;
  sigma[2] = A > 0 ? 0.5 * (s[first + 1] + s[first + 2]) / A : 0;
}

/* The stress columns: Love-Weber over the box's area, its principal values and q/p, and the walls' stresses. Zero
   without a box. */
static PetscErrorCode RecordStress(KergsResults res, const MacroBox *box, const PetscReal s[], const PetscReal sigma[],
                                   const PetscReal boundary[])
{
  const PetscReal W = box->x1 - box->x0, H = box->y1 - box->y0, A = box->found ? W * H : 0;
  PetscReal       s1 = 0, s2 = 0, wxx = 0, wyy = 0;

  PetscFunctionBeginUser;
  if (box->found) {
    wxx = 0.5 * (s[M_WALL + 0] + s[M_WALL + 1]) / H;
    wyy = 0.5 * (s[M_WALL + 2] + s[M_WALL + 3]) / W;
    Principal(sigma[0], sigma[1], sigma[2], &s1, &s2);
  }
  PetscCall(KergsResultsRecord(res, "box_area", A));
  PetscCall(KergsResultsRecord(res, "sxx", sigma[0]));
  PetscCall(KergsResultsRecord(res, "syy", sigma[1]));
  PetscCall(KergsResultsRecord(res, "sxy", sigma[2]));
  PetscCall(KergsResultsRecord(res, "s1", s1));
  PetscCall(KergsResultsRecord(res, "s2", s2));
  PetscCall(KergsResultsRecord(res, "q_over_p", s1 + s2 > 0 ? (s1 - s2) / (s1 + s2) : 0.0));
  PetscCall(KergsResultsRecord(res, "wall_sxx", wxx));
  PetscCall(KergsResultsRecord(res, "wall_syy", wyy));
  PetscCall(KergsResultsRecord(res, "boundary_sxx", boundary[0]));
  PetscCall(KergsResultsRecord(res, "boundary_syy", boundary[1]));
  PetscCall(KergsResultsRecord(res, "boundary_sxy", boundary[2]));
  PetscCall(KergsResultsRecord(res, "solid_fraction", box->found ? s[M_AREA] / A : 0.0));
  PetscFunctionReturn(0);
}

/* The network columns: coordination numbers, rattlers, anisotropies, sliding contacts. */
static PetscErrorCode RecordNetwork(KergsResults res, PetscInt ngrains, PetscInt nrattlers, PetscInt nends, const PetscReal s[])
{
  const PetscReal ncarrying = s[M_NDD] + s[M_NDW];
  PetscReal       a[3];

  PetscFunctionBeginUser;
  Anisotropies(s, a);
  PetscCall(KergsResultsRecord(res, "Z", ngrains > 0 ? (2 * s[M_NDD] + s[M_NDW]) / ngrains : 0.0));
  PetscCall(KergsResultsRecord(res, "Z_nonrattler", ngrains > nrattlers ? (PetscReal)nends / (ngrains - nrattlers) : 0.0));
  PetscCall(KergsResultsRecord(res, "rattler_fraction", ngrains > 0 ? (PetscReal)nrattlers / ngrains : 0.0));
  PetscCall(KergsResultsRecord(res, "a_c", a[0]));
  PetscCall(KergsResultsRecord(res, "a_n", a[1]));
  PetscCall(KergsResultsRecord(res, "a_t", a[2]));
  PetscCall(KergsResultsRecord(res, "sliding_fraction", ncarrying > 0 ? s[M_NSLIDE] / ncarrying : 0.0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsStepperRecordMacro(KergsStepper st)
{
  KergsDisks       D;
  const KergsWall *walls;
  KergsContact    *c;
  MacroBox         box;
  PetscInt         n, nwalls, nrattlers = 0, nends = 0;
  PetscReal        dt, s[M_NSUMS] = {0}, eps[3] = {0, 0, 0}, sigma[3], boundary[3];

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(KERGS_Macro, 0, 0, 0, 0));
  PetscCall(KergsSceneGetDisks(st->scene, &D));
  PetscCall(KergsSceneGetWalls(st->scene, &nwalls, &walls));
  PetscCall(KergsSceneGetTimeStep(st->scene, &dt, NULL));
  PetscCall(KergsContactsGetLocal(st->contacts, &n, &c));
  PetscCall(FindBox(nwalls, walls, &box));
  SumContacts(&D, n, c, &box, dt, s);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, s, M_NSUMS, MPIU_REAL, MPIU_SUM, st->comm));
  PetscCall(FindRattlers(st->comm, &D, n, c, &nrattlers, &nends));
  if (box.found) BoxStrains(walls, &box, eps);
  StressOverBox(&box, s, M_SXX, sigma);
  StressOverBox(&box, s, M_BXX, boundary);
  for (PetscInt i = 0; i < 3; i++) st->inertia_stress[i] = sigma[i] - boundary[i];
  st->inertia_found = box.found;
  PetscCall(RecordStress(st->results, &box, s, sigma, boundary));
  PetscCall(KergsResultsRecord(st->results, "strain_axial", eps[0]));
  PetscCall(KergsResultsRecord(st->results, "strain_lateral", eps[1]));
  PetscCall(KergsResultsRecord(st->results, "strain_volumetric", eps[2]));
  PetscCall(RecordNetwork(st->results, D.ndisks, nrattlers, nends, s));
  PetscCall(PetscLogEventEnd(KERGS_Macro, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
