/* kergs scene: where the disks come from (-disks_source): an explicit list, a lattice, a random
   non-overlapping sample, or a sample file of an earlier run. The generators are deterministic, so every rank
   builds the same disk set and KergsSceneSetDisks keeps its slice (O(N) per rank at the start of a run only). */
#include <kergs/private/sceneimpl.h>

typedef enum { DISKS_LIST, DISKS_LATTICE, DISKS_RANDOM, DISKS_FILE } DiskSource;
static const char *const DiskSources[] = {"list", "lattice", "random", "file"};

typedef enum { LATTICE_SQUARE, LATTICE_HEX } LatticeType;
/* How -disks_source random draws a radius in [rmin, rmax]: uniform in r, or uniform in area (pi r^2), the law of the
   standard polydisperse biaxial sample, which gives as much solid area to small as to large disks. */
typedef enum { RADIUS_UNIFORM, RADIUS_AREA } RadiusLaw;
static const char *const RadiusLaws[] = {"uniform", "area"};
/* The widest size ratio rmax/rmin the area law accepts: the cells are sized for rmax, so a wider ratio wastes most
   of the box, and the biaxial literature stays within it. */
#define KERGS_RADIUS_RATIO_MAX 10.0
static const char *const LatticeTypes[] = {"square", "hex"};

/* Everything the disk options say, read at once so that -help lists every source's options. */
typedef struct {
  PetscInt source;
  /* -disks_material, for every source but file */
  PetscInt  nmat, *mat;
  PetscBool mat_set;
  /* list */
  PetscInt   nx, nr, nv;
  PetscReal *x, *r, *v;
  PetscBool  x_set;
  /* lattice */
  PetscInt  lattice_type, nlat, *lattice_n;
  PetscReal lattice_radius, lattice_origin[KERGS_DIM], lattice_spacing;
  PetscBool lattice_n_set, lattice_spacing_set;
  /* random */
  PetscInt  random_n, random_seed, random_radius_law;
  PetscReal random_box[4], random_radius[2];
  PetscBool random_box_set, random_radius_set;
  /* file */
  char      sample[PETSC_MAX_PATH_LEN];
  PetscBool sample_set;
} DiskOptions;

static PetscErrorCode DiskOptionsRead(MPI_Comm comm, DiskOptions *o)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Scene disk options", NULL);
  PetscCall(
      PetscOptionsEList("-disks_source", "Where the disks come from", NULL, DiskSources, 4, DiskSources[o->source], &o->source, NULL));
  PetscCall(KergsOptionsIntList(PetscOptionsObject, "-disks_material", "Material of the disks: one value for all, or one per disk",
                                &o->nmat, &o->mat, &o->mat_set));
  PetscCall(KergsOptionsRealList(PetscOptionsObject, "-disks_x", "list: disk centres x0,y0,x1,y1,...", &o->nx, &o->x, &o->x_set));
  PetscCall(KergsOptionsRealList(PetscOptionsObject, "-disks_radius", "list: radius of all disks, or r0,r1,...", &o->nr, &o->r, NULL));
  PetscCall(
      KergsOptionsRealList(PetscOptionsObject, "-disks_velocity", "list: initial velocities vx0,vy0,... (default 0)", &o->nv, &o->v, NULL));
  PetscCall(PetscOptionsEList("-lattice_type", "lattice: square or hex", NULL, LatticeTypes, 2, LatticeTypes[o->lattice_type],
                              &o->lattice_type, NULL));
  PetscCall(
      KergsOptionsIntList(PetscOptionsObject, "-lattice_n", "lattice: number of disks nx,ny", &o->nlat, &o->lattice_n, &o->lattice_n_set));
  PetscCall(PetscOptionsReal("-lattice_radius", "lattice: radius of the disks", NULL, o->lattice_radius, &o->lattice_radius, NULL));
  PetscCall(KergsOptionsVector(PetscOptionsObject, "-lattice_origin", "lattice: centre x,y of the first disk", o->lattice_origin, NULL));
  PetscCall(PetscOptionsReal("-lattice_spacing", "lattice: distance between neighbour centres (default 2 * radius: touching)", NULL,
                             o->lattice_spacing, &o->lattice_spacing, &o->lattice_spacing_set));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-random_n", "random: number of disks", NULL, o->random_n, &o->random_n, NULL));
  PetscCall(KergsOptionsReals(PetscOptionsObject, "-random_box", "random: box x0,y0,x1,y1 that holds the disks", 4, o->random_box,
                              &o->random_box_set));
  PetscCall(KergsOptionsReals(PetscOptionsObject, "-random_radius", "random: radius range rmin,rmax (uniform distribution)", 2,
                              o->random_radius, &o->random_radius_set));
  PetscCall(PetscOptionsEList("-random_radius_law", "random: law of the radius in [rmin, rmax]: uniform in r, or uniform in area", NULL,
                              RadiusLaws, 2, RadiusLaws[o->random_radius_law], &o->random_radius_law, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-random_seed", "random: seed of the generator (same seed, same sample)", NULL,
                            o->random_seed, &o->random_seed, NULL));
  PetscCall(PetscOptionsString("-sample_input", "file: sample file (HDF5) of an earlier run", NULL, o->sample, o->sample, sizeof(o->sample),
                               &o->sample_set));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

static PetscErrorCode DiskOptionsDestroy(DiskOptions *o)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(o->mat));
  PetscCall(PetscFree(o->lattice_n));
  PetscCall(PetscFree(o->x));
  PetscCall(PetscFree(o->r));
  PetscCall(PetscFree(o->v));
  PetscFunctionReturn(0);
}

/* The material of n generated disks from -disks_material: none (0), one for all, or one per disk. */
static PetscErrorCode DiskMaterials(MPI_Comm comm, const DiskOptions *o, PetscInt n, PetscInt **mat)
{
  PetscFunctionBeginUser;
  PetscCheck(o->nmat <= 1 || o->nmat == n, comm, PETSC_ERR_ARG_SIZ,
             "-disks_material has %" PetscInt_FMT " values for %" PetscInt_FMT " disks: give 1 or %" PetscInt_FMT, o->nmat, n, n);
  PetscCall(PetscCalloc1(n, mat));
  for (PetscInt i = 0; i < n && o->nmat; i++) (*mat)[i] = o->mat[o->nmat == 1 ? 0 : i];
  PetscFunctionReturn(0);
}

/* list: -disks_x (KERGS_DIM * N values), -disks_radius (1 or N), -disks_velocity (0 or KERGS_DIM * N).
   Without -disks_x the scene keeps the disks it has (none for a new scene). */
static PetscErrorCode DisksFromList(KergsScene scene, const DiskOptions *o)
{
  MPI_Comm   comm = scene->comm;
  PetscInt   n, *mat;
  PetscReal *r;

  PetscFunctionBeginUser;
  if (!o->x_set) {
    PetscCheck(!o->nr && !o->nv && !o->mat_set, comm, PETSC_ERR_ARG_WRONGSTATE,
               "-disks_radius, -disks_velocity or -disks_material given without -disks_x");
    PetscFunctionReturn(0);
  }
  PetscCheck(o->nx % KERGS_DIM == 0, comm, PETSC_ERR_ARG_SIZ, "-disks_x has %" PetscInt_FMT " values, not a multiple of %d (x,y per disk)",
             o->nx, KERGS_DIM);
  n = o->nx / KERGS_DIM;
  PetscCheck(n == 0 || o->nr == 1 || o->nr == n, comm, PETSC_ERR_ARG_SIZ,
             "-disks_radius has %" PetscInt_FMT " values for %" PetscInt_FMT " disks of -disks_x: give 1 or %" PetscInt_FMT, o->nr, n, n);
  PetscCheck(o->nv == 0 || o->nv == KERGS_DIM * n, comm, PETSC_ERR_ARG_SIZ,
             "-disks_velocity has %" PetscInt_FMT " values for %" PetscInt_FMT " disks: give %" PetscInt_FMT, o->nv, n, KERGS_DIM * n);
  PetscCall(DiskMaterials(comm, o, n, &mat));
  PetscCall(PetscMalloc1(n, &r));
  for (PetscInt i = 0; i < n; i++) r[i] = o->r[o->nr == 1 ? 0 : i];
  PetscCall(KergsSceneSetDisks(scene, n, o->x, r, mat, o->nv ? o->v : NULL));
  PetscCall(PetscFree(r));
  PetscCall(PetscFree(mat));
  PetscFunctionReturn(0);
}

/* lattice: nx x ny disks of one radius. Square: centres on a grid of pitch s. Hex: rows at height s sqrt(3)/2,
   odd rows shifted by s/2, so that every neighbour (in the row and in the next rows) is at distance s. */
static PetscErrorCode DisksFromLattice(KergsScene scene, const DiskOptions *o)
{
  MPI_Comm        comm = scene->comm;
  const PetscReal rad  = o->lattice_radius;
  PetscReal       s, *x, *r;
  PetscInt        nx, ny, n, *mat;

  PetscFunctionBeginUser;
  PetscCheck(o->lattice_n_set && o->nlat == 2, comm, PETSC_ERR_ARG_SIZ,
             "-disks_source lattice needs -lattice_n nx,ny (2 values, got %" PetscInt_FMT ")", o->nlat);
  nx = o->lattice_n[0];
  ny = o->lattice_n[1];
  PetscCheck(nx > 0 && ny > 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-lattice_n %" PetscInt_FMT ",%" PetscInt_FMT ": both must be positive", nx,
             ny);
  PetscCheck(rad > 0.0 && !PetscIsInfOrNanReal(rad), comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-disks_source lattice needs -lattice_radius > 0 (got %g)", (double)rad);
  PetscCheck((PetscInt64)nx * (PetscInt64)ny <= KERGS_MAX_DISKS, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-lattice_n %" PetscInt_FMT ",%" PetscInt_FMT " asks for %" PetscInt64_FMT " disks; this build counts in %d-bit integers "
             "(PetscInt) and holds at most %" PetscInt_FMT " disks",
             nx, ny, (PetscInt64)nx * (PetscInt64)ny, (int)(8 * sizeof(PetscInt)), (PetscInt)KERGS_MAX_DISKS);
  s = o->lattice_spacing_set ? o->lattice_spacing : 2.0 * rad;
  PetscCheck(s >= 2.0 * rad, comm, PETSC_ERR_ARG_OUTOFRANGE, "-lattice_spacing %g is less than 2 * radius = %g: the disks would overlap",
             (double)s, (double)(2.0 * rad));
  n = nx * ny;
  PetscCall(PetscMalloc2(KERGS_DIM * n, &x, n, &r));
  for (PetscInt j = 0; j < ny; j++) {
    for (PetscInt i = 0; i < nx; i++) {
      const PetscInt k = j * nx + i;

      if (o->lattice_type == LATTICE_HEX) {
        x[KERGS_DIM * k]     = o->lattice_origin[0] + (i + (j % 2 ? 0.5 : 0.0)) * s;
        x[KERGS_DIM * k + 1] = o->lattice_origin[1] + j * s * PetscSqrtReal(3.0) / 2.0;
      } else {
        x[KERGS_DIM * k]     = o->lattice_origin[0] + i * s;
        x[KERGS_DIM * k + 1] = o->lattice_origin[1] + j * s;
      }
      r[k] = rad;
    }
  }
  PetscCall(DiskMaterials(comm, o, n, &mat));
  PetscCall(KergsSceneSetDisks(scene, n, x, r, mat, NULL));
  PetscCall(PetscFree(mat));
  PetscCall(PetscFree2(x, r));
  PetscFunctionReturn(0);
}

/* A radius in [rmin, rmax] from a uniform draw u in [0, 1): r = rmin + (rmax - rmin) u, or for the area law
   r = sqrt(rmin^2 + (rmax^2 - rmin^2) u), so that r^2 is uniform in [rmin^2, rmax^2]. */
static PetscReal RandomRadius(RadiusLaw law, PetscReal rmin, PetscReal rmax, PetscReal u)
{
  if (law == RADIUS_AREA) return PetscSqrtReal(rmin * rmin + (rmax * rmax - rmin * rmin) * u);
  return rmin + (rmax - rmin) * u;
}

/* random: the box is cut into square cells of side 2 rmax + gap, filled row by row from the bottom left, one disk
   per cell with a radius in [rmin, rmax] drawn by -random_radius_law and its centre moved by a uniform offset of at most rmax - r in
   each direction. A disk stays gap/2 inside its cell, so no two disks overlap. Three draws per disk from
   rand48 with the given seed: the same sample on every rank and for every number of ranks. */
static PetscErrorCode DisksFromRandom(KergsScene scene, const DiskOptions *o)
{
  MPI_Comm        comm = scene->comm;
  const PetscReal rmin = o->random_radius[0], rmax = o->random_radius[1], *box = o->random_box;
  const PetscReal gap = 1e-3 * rmax, cell = 2.0 * rmax + gap;
  const PetscInt  n = o->random_n;
  PetscReal      *x, *r, ncx_real, ncy_real;
  PetscInt        ncx, *mat;
  PetscRandom     rnd;

  PetscFunctionBeginUser;
  PetscCheck(n >= 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-random_n %" PetscInt_FMT " must be at least 1: a packing of no grain", n);
  PetscCheck(n <= KERGS_MAX_DISKS, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-random_n %" PetscInt_FMT ": this build counts in %d-bit integers (PetscInt) and holds at most %" PetscInt_FMT " disks", n,
             (int)(8 * sizeof(PetscInt)), (PetscInt)KERGS_MAX_DISKS);
  PetscCheck(o->random_box_set, comm, PETSC_ERR_ARG_WRONGSTATE, "-disks_source random needs -random_box x0,y0,x1,y1");
  PetscCheck(box[2] > box[0] && box[3] > box[1], comm, PETSC_ERR_ARG_OUTOFRANGE, "-random_box %g,%g,%g,%g: need x0 < x1 and y0 < y1",
             (double)box[0], (double)box[1], (double)box[2], (double)box[3]);
  PetscCheck(o->random_radius_set, comm, PETSC_ERR_ARG_WRONGSTATE, "-disks_source random needs -random_radius rmin,rmax");
  PetscCheck(rmin > 0.0 && rmax >= rmin && !PetscIsInfOrNanReal(rmax), comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-random_radius %g,%g: need 0 < rmin <= rmax", (double)rmin, (double)rmax);
  PetscCheck(o->random_radius_law != RADIUS_AREA || rmax <= KERGS_RADIUS_RATIO_MAX * rmin, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-random_radius %g,%g with -random_radius_law area: the ratio rmax/rmin = %g is above %g", (double)rmin, (double)rmax,
             (double)(rmax / rmin), (double)KERGS_RADIUS_RATIO_MAX);
  ncx_real = PetscFloorReal((box[2] - box[0]) / cell);
  ncy_real = PetscFloorReal((box[3] - box[1]) / cell);
  PetscCheck(ncx_real * ncy_real >= (PetscReal)n, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-random_box %g x %g holds only %.0f cells of side %g (2 * rmax + gap), fewer than -random_n %" PetscInt_FMT
             ": enlarge the box or reduce rmax",
             (double)(box[2] - box[0]), (double)(box[3] - box[1]), (double)(ncx_real * ncy_real), (double)cell, n);
  ncx = (PetscInt)ncx_real;
  PetscCall(PetscRandomCreate(PETSC_COMM_SELF, &rnd));
  PetscCall(PetscRandomSetType(rnd, PETSCRAND48));
  PetscCall(PetscRandomSetSeed(rnd, (unsigned long)o->random_seed));
  PetscCall(PetscRandomSeed(rnd));
  PetscCall(PetscMalloc2(KERGS_DIM * n, &x, n, &r));
  for (PetscInt k = 0; k < n; k++) {
    const PetscInt i = k % ncx, j = k / ncx;
    PetscReal      u[3], slack;

    for (PetscInt d = 0; d < 3; d++) PetscCall(PetscRandomGetValueReal(rnd, &u[d]));
    r[k]                 = RandomRadius((RadiusLaw)o->random_radius_law, rmin, rmax, u[0]);
    slack                = rmax - r[k];
    x[KERGS_DIM * k]     = box[0] + (i + 0.5) * cell + (2.0 * u[1] - 1.0) * slack;
    x[KERGS_DIM * k + 1] = box[1] + (j + 0.5) * cell + (2.0 * u[2] - 1.0) * slack;
  }
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(DiskMaterials(comm, o, n, &mat));
  PetscCall(KergsSceneSetDisks(scene, n, x, r, mat, NULL));
  PetscCall(PetscFree(mat));
  PetscCall(PetscFree2(x, r));
  PetscFunctionReturn(0);
}

static PetscErrorCode DisksFromFile(KergsScene scene, const DiskOptions *o)
{
  PetscFunctionBeginUser;
  PetscCheck(o->sample_set && o->sample[0], scene->comm, PETSC_ERR_ARG_WRONGSTATE, "-disks_source file needs -sample_input <path>");
  PetscCall(KergsSampleRead(scene, o->sample));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneDisksSourceFromOptions(char source[], size_t len)
{
  PetscFunctionBeginUser;
  PetscCall(PetscStrncpy(source, DiskSources[DISKS_LIST], len)); /* DiskOptionsRead's default */
  PetscCall(PetscOptionsGetString(NULL, NULL, "-disks_source", source, len, NULL));
  PetscFunctionReturn(0);
}

/* The disk options block (-disks_source and the options of every source) and the generation of the disks. */
PetscErrorCode KergsSceneDisksSetFromOptions(KergsScene scene)
{
  DiskOptions o;
  PetscBool   help;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(&o, sizeof(o)));
  o.source       = DISKS_LIST;
  o.lattice_type = LATTICE_SQUARE;
  o.random_seed  = 1;
  PetscCall(DiskOptionsRead(scene->comm, &o));
  if (scene->restoring) o.source = -1; /* read (for -help and the unused-option check), but the checkpoint holds the disks */
  /* not on a restart (source -1 above: the checkpoint holds the disks), nor in the -help pass that looks for options
     without a value (main's KergsOptionsCheckValues, where a restart is not marked as one) */
  PetscCall(PetscOptionsHasHelp(NULL, &help));
  PetscCheck(o.source < 0 || o.source == DISKS_FILE || !o.sample_set || help, scene->comm, PETSC_ERR_ARG_INCOMP,
             "-sample_input %s is read only with -disks_source file, and the disks come from -disks_source %s: drop one", o.sample,
             DiskSources[o.source]);
  switch ((DiskSource)o.source) {
  case DISKS_LIST:
    PetscCall(DisksFromList(scene, &o));
    break;
  case DISKS_LATTICE:
    PetscCall(DisksFromLattice(scene, &o));
    break;
  case DISKS_RANDOM:
    PetscCall(DisksFromRandom(scene, &o));
    break;
  case DISKS_FILE:
    PetscCall(DisksFromFile(scene, &o));
    break;
  default:
    break;
  }
  PetscCall(DiskOptionsDestroy(&o));
  PetscFunctionReturn(0);
}
