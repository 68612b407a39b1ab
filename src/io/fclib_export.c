/* kergs FCLib export: one step's local problem u = W r + q with Coulomb's law (W, q = v^d, mu) in the FCLib
   HDF5 format, written by Debian's libfclib so that other solvers (Siconos fc2d) can solve the very problem
   kergs solved. Layout in docs/results.md.

   libfclib is linked against the serial HDF5 while PETSc uses the MPI one: both libraries export the same
   symbols. It is therefore never linked: it is loaded with dlopen(RTLD_LOCAL | RTLD_DEEPBIND) so that its
   HDF5 calls bind to its own serial HDF5, and only rank 0 calls it. libfclib exits the process on an HDF5
   failure, so everything it is given is checked first. */
#define _GNU_SOURCE /* RTLD_DEEPBIND */
#include <kergs/fclib.h>
#include <kergs/results.h>
#include <kergs/files.h>
#include <dlfcn.h>
#include <limits.h>
#include <stdio.h>
#include <fclib.h>

#ifndef KERGS_FCLIB_LIBRARY
#define KERGS_FCLIB_LIBRARY "libfclib.so.0"
#endif

#define KERGS_FCLIB_SPACEDIM 2         /* FCLib's 2D frictional contact: normal then tangential per contact */
#define KERGS_FCLIB_PACK 5             /* per exported contact: q_n, q_t, mu, r_n, r_t */
#define KERGS_FCLIB_HDF5_BYTES 32768.0 /* HDF5's groups, attributes and texts around the data: 13 KB measured for 5 contacts */

typedef int (*FCLibWriteLocalFn)(struct fclib_local *, const char *);
typedef int (*FCLibWriteSolutionFn)(struct fclib_solution *, const char *);

/* A function of libfclib, loaded once (rank 0 only; also for src/io/fclib_import.c); msg is set when the library or the
   function is missing. */
void KergsFCLibSymbol(const char name[], void **fn, char msg[], size_t len)
{
  static void *handle  = NULL; /* never closed: unloading an HDF5 library at run time is not safe */
  const char  *names[] = {KERGS_FCLIB_LIBRARY, "libfclib.so.0"};

  *fn = NULL;
  for (size_t k = 0; !handle && k < sizeof(names) / sizeof(names[0]); k++) handle = dlopen(names[k], RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
  if (!handle) {
    snprintf(msg, len, "Cannot load libfclib (%s): %s", KERGS_FCLIB_LIBRARY, dlerror());
    return;
  }
  *fn = dlsym(handle, name);
  if (!*fn) snprintf(msg, len, "libfclib (%s) lacks %s", KERGS_FCLIB_LIBRARY, name);
}

/* Load libfclib's writers; msg is set when one is missing. */
static void FCLibLoad(FCLibWriteLocalFn *write_local, FCLibWriteSolutionFn *write_solution, char msg[], size_t len)
{
  KergsFCLibSymbol("fclib_write_local", (void **)write_local, msg, len);
  if (!msg[0]) KergsFCLibSymbol("fclib_write_solution", (void **)write_solution, msg, len);
}

/* The exported problem on rank 0: na contacts, m = 2 na unknowns, W in compressed columns (FCLib nz = -1). */
typedef struct {
  PetscInt  na, m, nnz;
  int      *colptr, *rowind;
  double   *val, *q, *mu, *r, *u;
  PetscBool padded; /* frictionless kergs problem: tangential components added */
} FCLibProblem;

static PetscErrorCode FCLibProblemFree(FCLibProblem *p)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree3(p->colptr, p->rowind, p->val));
  PetscCall(PetscFree4(p->q, p->mu, p->r, p->u));
  PetscFunctionReturn(0);
}

/* Global row indices of W (contact components) of this rank's active contacts, gathered on rank 0 in
   order; also the per-contact pack (q_n, q_t, mu, r_n, r_t) of those contacts. */
static PetscErrorCode FCLibGather(MPI_Comm comm, PetscInt n, const KergsContact *contacts, PetscInt nc, Vec vdv, const PetscBool *active,
                                  PetscInt rstart, PetscInt *na, PetscInt **rows, PetscReal **pack)
{
  PetscMPIInt        rank, size, nloc = 0, ntot = 0, *counts = NULL, *displs = NULL;
  PetscInt          *lrows;
  PetscReal         *lpack;
  const PetscScalar *vd;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  for (PetscInt k = 0; k < n; k++)
    if (active[k]) nloc++;
  PetscCall(PetscMalloc2(nloc * nc, &lrows, nloc * KERGS_FCLIB_PACK, &lpack));
  PetscCall(VecGetArrayRead(vdv, &vd));
  for (PetscInt k = 0, a = 0; k < n; k++) {
    const KergsContact *c = &contacts[k];
    if (!active[k]) continue;
    for (PetscInt j = 0; j < nc; j++) lrows[a * nc + j] = rstart + k * nc + j;
    lpack[a * KERGS_FCLIB_PACK + 0] = PetscRealPart(vd[k * nc]);
    lpack[a * KERGS_FCLIB_PACK + 1] = nc > 1 ? PetscRealPart(vd[k * nc + 1]) : 0.0;
    lpack[a * KERGS_FCLIB_PACK + 2] = nc > 1 ? c->mu : 0.0;
    lpack[a * KERGS_FCLIB_PACK + 3] = c->r[0];
    lpack[a * KERGS_FCLIB_PACK + 4] = nc > 1 ? c->r[1] : 0.0;
    a++;
  }
  PetscCall(VecRestoreArrayRead(vdv, &vd));
  if (rank == 0) PetscCall(PetscMalloc2(size, &counts, size + 1, &displs));
  PetscCallMPI(MPI_Gather(&nloc, 1, MPI_INT, counts, 1, MPI_INT, 0, comm));
  if (rank == 0) {
    displs[0] = 0;
    for (PetscMPIInt p = 0; p < size; p++) displs[p + 1] = displs[p] + counts[p];
    ntot = displs[size];
  }
  *na = ntot;
  PetscCall(PetscMalloc2(ntot * nc, rows, ntot * KERGS_FCLIB_PACK, pack));
  /* rows: counts and displacements in units of contacts, scaled to components and packs */
  if (rank == 0)
    for (PetscMPIInt p = 0; p <= size; p++) {
      if (p < size) counts[p] *= (PetscMPIInt)nc;
      displs[p] *= (PetscMPIInt)nc;
    }
  PetscCallMPI(MPI_Gatherv(lrows, (PetscMPIInt)(nloc * nc), MPIU_INT, *rows, counts, displs, MPIU_INT, 0, comm));
  if (rank == 0)
    for (PetscMPIInt p = 0; p <= size; p++) {
      if (p < size) counts[p] = counts[p] / (PetscMPIInt)nc * KERGS_FCLIB_PACK;
      displs[p] = displs[p] / (PetscMPIInt)nc * KERGS_FCLIB_PACK;
    }
  PetscCallMPI(MPI_Gatherv(lpack, nloc * KERGS_FCLIB_PACK, MPIU_REAL, *pack, counts, displs, MPIU_REAL, 0, comm));
  if (rank == 0) PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree2(lrows, lpack));
  PetscFunctionReturn(0);
}

/* Padded index of component j of the exported (active-only) kergs numbering: contact j / nc, normal or
   tangential j % nc; FCLib always has 2 components per contact. */
static inline PetscInt FCLibIndex(PetscInt j, PetscInt nc) { return (j / nc) * KERGS_FCLIB_SPACEDIM + j % nc; }

/* Compressed columns of the padded W from the sequential submatrix Wa (rows and columns of the active
   contacts). Frictionless: each contact gets a tangential unknown with W_tt = W_nn and no coupling, so the
   padded problem has the same normal solution and r_t = 0. Rows are visited in increasing padded order, so
   row indices come out sorted inside each column. */
static PetscErrorCode FCLibBuildCSC(Mat Wa, PetscInt nc, FCLibProblem *p)
{
  const PetscInt     nrows = p->na * nc;
  PetscInt          *count, *next, ncols;
  const PetscInt    *cols;
  const PetscScalar *vals;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc2(p->m + 1, &count, p->m, &next));
  p->nnz = 0;
  for (PetscInt i = 0; i < nrows; i++) {
    PetscCall(MatGetRow(Wa, i, &ncols, &cols, NULL));
    for (PetscInt e = 0; e < ncols; e++) count[FCLibIndex(cols[e], nc)]++;
    p->nnz += ncols;
    PetscCall(MatRestoreRow(Wa, i, &ncols, &cols, NULL));
    if (p->padded) {
      count[FCLibIndex(i, nc) + 1]++;
      p->nnz++;
    }
  }
  PetscCheck(p->nnz < INT_MAX && p->m < INT_MAX, PETSC_COMM_SELF, PETSC_ERR_SUP,
             "FCLib export: W with %" PetscInt_FMT " entries does not fit FCLib's int indices", p->nnz);
  /* at least one entry each: libfclib exits on a NULL array, even an empty one */
  PetscCall(PetscMalloc3(p->m + 1, &p->colptr, PetscMax(p->nnz, 1), &p->rowind, PetscMax(p->nnz, 1), &p->val));
  p->colptr[0] = 0;
  for (PetscInt j = 0; j < p->m; j++) {
    p->colptr[j + 1] = p->colptr[j] + (int)count[j];
    next[j]          = p->colptr[j];
  }
  for (PetscInt i = 0; i < nrows; i++) {
    const PetscInt pi   = FCLibIndex(i, nc);
    PetscReal      diag = 0.0;
    PetscCall(MatGetRow(Wa, i, &ncols, &cols, &vals));
    for (PetscInt e = 0; e < ncols; e++) {
      const PetscInt pj   = FCLibIndex(cols[e], nc);
      p->rowind[next[pj]] = (int)pi;
      p->val[next[pj]++]  = PetscRealPart(vals[e]);
      if (cols[e] == i) diag = PetscRealPart(vals[e]);
    }
    PetscCall(MatRestoreRow(Wa, i, &ncols, &cols, &vals));
    if (p->padded) { /* row pi + 1 holds only its diagonal, W_tt = W_nn */
      p->rowind[next[pi + 1]] = (int)(pi + 1);
      p->val[next[pi + 1]++]  = diag;
    }
  }
  PetscCall(PetscFree2(count, next));
  PetscFunctionReturn(0);
}

/* q, mu, r from the gathered packs; u = W r + q, the local velocity of the exported problem. */
static PetscErrorCode FCLibBuildVectors(const PetscReal *pack, FCLibProblem *p)
{
  PetscFunctionBeginUser;
  PetscCall(PetscMalloc4(PetscMax(p->m, 1), &p->q, PetscMax(p->na, 1), &p->mu, PetscMax(p->m, 1), &p->r, PetscMax(p->m, 1), &p->u));
  for (PetscInt a = 0; a < p->na; a++) {
    const PetscReal *pk = pack + a * KERGS_FCLIB_PACK;
    p->q[2 * a]         = pk[0];
    p->q[2 * a + 1]     = pk[1];
    p->mu[a]            = pk[2];
    p->r[2 * a]         = pk[3];
    p->r[2 * a + 1]     = pk[4];
  }
  for (PetscInt i = 0; i < p->m; i++) p->u[i] = p->q[i];
  for (PetscInt j = 0; j < p->m; j++)
    for (int e = p->colptr[j]; e < p->colptr[j + 1]; e++) p->u[p->rowind[e]] += p->val[e] * p->r[j];
  PetscFunctionReturn(0);
}

/* The texts of /fclib_local/info: the title, the description's head (FCLibWrite adds the contacts and the padding) and
   the meaning of W and r. */
typedef struct {
  const char *title, *head, *math;
} FCLibText;

/* Rank 0: write path.tmp with libfclib, then rename it to path; msg is set on failure. */
static PetscErrorCode FCLibWrite(FCLibProblem *p, const FCLibText *text, const char path[], char msg[], size_t len)
{
  FCLibWriteLocalFn     write_local    = NULL;
  FCLibWriteSolutionFn  write_solution = NULL;
  char                  tmp[PETSC_MAX_PATH_LEN], description[PETSC_MAX_PATH_LEN + 256];
  struct fclib_matrix   W;
  struct fclib_info     info;
  struct fclib_local    problem;
  struct fclib_solution solution;

  PetscFunctionBeginUser;
  FCLibLoad(&write_local, &write_solution, msg, len);
  if (msg[0]) PetscFunctionReturn(0);
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", path));
  PetscCall(PetscSNPrintf(description, sizeof(description),
                          "%s, %" PetscInt_FMT " active contacts%s; unknowns per contact normal then tangential", text->head, p->na,
                          p->padded ? ", frictionless (tangential components padded: W_tt = W_nn, q_t = 0, mu = 0)" : ""));
  W = (struct fclib_matrix){
      .nzmax = (int)p->nnz, .m = (int)p->m, .n = (int)p->m, .p = p->colptr, .i = p->rowind, .x = p->val, .nz = -1, .info = NULL};
  info    = (struct fclib_info){.title = (char *)text->title, .description = description, .math_info = (char *)text->math};
  problem = (struct fclib_local){
      .W = &W, .V = NULL, .R = NULL, .mu = p->mu, .q = p->q, .s = NULL, .spacedim = KERGS_FCLIB_SPACEDIM, .info = &info};
  solution = (struct fclib_solution){.v = NULL, .u = p->u, .r = p->r, .l = NULL};
  if (!KergsFileReplaceable(path, msg, len) || !KergsFileReplaceable(tmp, msg, len)) PetscFunctionReturn(0);
  (void)remove(tmp); /* libfclib refuses to write a local problem into a file that already holds one */
  if (!write_local(&problem, tmp))
    snprintf(msg, len, "libfclib could not write the local problem to %s", tmp);
  else if (p->m > 0 && !write_solution(&solution, tmp)) /* libfclib exits on an empty solution: none then */
    snprintf(msg, len, "libfclib could not write the solution to %s", tmp);
  else if (!KergsFileReplaceable(path, msg, len)) /* it became one since the check: the .tmp is kept */
    PetscFunctionReturn(0);
  else if (rename(tmp, path))
    snprintf(msg, len, "Cannot rename %s to %s", tmp, path);
  PetscFunctionReturn(0);
}

/* The problem of the active contacts, with their impulses as its solution, written to path by rank 0. Collective. */
static PetscErrorCode FCLibExport(KergsContacts contacts, KergsOperators ops, const PetscBool *active, const FCLibText *text,
                                  const char path[])
{
  MPI_Comm       comm;
  PetscMPIInt    rank;
  PetscInt       nc, rstart, rend, vlo, vhi, *rows = NULL, n;
  PetscReal     *pack = NULL;
  IS             is;
  Mat           *sub, W;
  Vec            vd;
  KergsContact  *c;
  KergsDofLayout layout;
  FCLibProblem   p                                 = {0};
  PetscReal      bytes                             = 0.0;
  char           msg[2 * PETSC_MAX_PATH_LEN + 128] = "";

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(KergsOperatorsGetLayout(ops, &layout));
  PetscCall(KergsOperatorsGetW(ops, &W, NULL));
  PetscCall(KergsOperatorsGetContactVectors(ops, NULL, NULL, &vd));
  PetscCall(KergsContactsGetLocal(contacts, &n, &c));
  PetscCheck(W && vd, PETSC_COMM_SELF, PETSC_ERR_ORDER, "FCLib export to %s: assemble the operators (W, v^d) first", path);
  comm = PetscObjectComm((PetscObject)W);
  nc   = layout.ncomp;
  PetscCheck(path && path[0], comm, PETSC_ERR_ARG_WRONG, "FCLib export: empty file name");
  PetscCheck(nc == 1 || nc == KERGS_FCLIB_SPACEDIM, comm, PETSC_ERR_SUP,
             "FCLib export: %" PetscInt_FMT " components per contact; FCLib 2D needs 1 (padded) or 2", nc);
  PetscCheck(!n || active, comm, PETSC_ERR_ARG_NULL, "FCLib export to %s: no active-contact flags", path);
  PetscCall(MatGetOwnershipRange(W, &rstart, &rend));
  PetscCall(VecGetOwnershipRange(vd, &vlo, &vhi));
  PetscCheck(rend - rstart == n * nc && vlo == rstart && vhi == rend, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ,
             "FCLib export to %s: W rows [%" PetscInt_FMT ", %" PetscInt_FMT ") and v^d [%" PetscInt_FMT ", %" PetscInt_FMT
             ") do not match this rank's %" PetscInt_FMT " contacts x %" PetscInt_FMT " components",
             path, rstart, rend, vlo, vhi, n, nc);
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(KergsFileMakeParentDir(comm, path));
  PetscCall(FCLibGather(comm, n, c, nc, vd, active, rstart, &p.na, &rows, &pack));
  /* W restricted to the active contacts, as one sequential matrix on rank 0 (empty elsewhere) */
  PetscCall(ISCreateGeneral(PETSC_COMM_SELF, p.na * nc, rows, PETSC_USE_POINTER, &is));
  PetscCall(ISSetBlockSize(is, nc)); /* whole contacts: BAIJ W extracts by blocks only */
  {
    Mat Wfull; /* whole rows: W itself is stored by its upper triangle */
    PetscCall(KergsOperatorsGetFullW(ops, &Wfull));
    PetscCall(MatCreateSubMatrices(Wfull, 1, &is, &is, MAT_INITIAL_MATRIX, &sub));
    PetscCall(MatDestroy(&Wfull));
  }
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    p.m      = KERGS_FCLIB_SPACEDIM * p.na;
    p.padded = (PetscBool)(nc == 1);
    PetscCall(FCLibBuildCSC(sub[0], nc, &p));
    PetscCall(FCLibBuildVectors(pack, &p));
    bytes = 12.0 * (PetscReal)p.nnz + 8.0 * (PetscReal)(6 * p.m + p.na) + KERGS_FCLIB_HDF5_BYTES;
  }
  PetscCallMPI(MPI_Bcast(&bytes, 1, MPIU_REAL, 0, comm));
  { /* libfclib exits the process when a write fails: a full file system is refused before it writes */
    PetscErrorCode ierr = KergsFileCheckSpace(comm, path, NULL, "the FCLib problem", bytes);
    if (ierr && rank == 0) PetscCall(FCLibProblemFree(&p));
    PetscCall(ierr);
  }
  if (rank == 0) {
    PetscCall(FCLibWrite(&p, text, path, msg, sizeof(msg)));
    PetscCall(FCLibProblemFree(&p));
  }
  PetscCall(MatDestroySubMatrices(1, &sub));
  PetscCall(ISDestroy(&is));
  PetscCall(PetscFree2(rows, pack));
  PetscCallMPI(MPI_Bcast(msg, (int)sizeof(msg), MPI_CHAR, 0, comm));
  PetscCheck(msg[0] == 0, comm, PETSC_ERR_FILE_WRITE, "FCLib export: %s", msg);
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibExport(KergsScene scene, KergsContacts contacts, KergsOperators ops, const PetscBool *active, const char path[])
{
  const char *name = "";
  PetscInt    step = 0;
  PetscReal   time = 0;
  char        title[PETSC_MAX_PATH_LEN + 64], head[128];

  PetscFunctionBeginUser;
  if (scene) {
    PetscCall(KergsSceneGetName(scene, &name));
    PetscCall(KergsSceneGetStep(scene, &step, &time, NULL));
    step++; /* exported after the solve, before the clock advances: the step line of this step says step + 1 */
  }
  PetscCall(PetscSNPrintf(title, sizeof(title), "kergs %s step %" PetscInt_FMT, name, step));
  PetscCall(PetscSNPrintf(head, sizeof(head), "2D disks, step from time %g", (double)time));
  PetscCall(FCLibExport(contacts, ops, active,
                        &(FCLibText){title, head,
                                     "W = H_f^T M^-1 H_f symmetric positive semi-definite (singular in confined packings); solution r is "
                                     "kergs' impulse, u = W r + q"},
                        path));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibExportSolved(KergsContacts contacts, KergsOperators ops, const char source[], const char path[])
{
  PetscInt   n;
  PetscBool *all;
  char       title[PETSC_MAX_PATH_LEN + 64];

  PetscFunctionBeginUser;
  PetscCall(KergsContactsGetLocal(contacts, &n, NULL));
  PetscCall(PetscMalloc1(PetscMax(n, 1), &all));
  for (PetscInt k = 0; k < n; k++) all[k] = PETSC_TRUE; /* every contact of an FCLib problem holds its law */
  PetscCall(PetscSNPrintf(title, sizeof(title), "kergs solution of %s", source));
  PetscCall(
      FCLibExport(contacts, ops, all,
                  &(FCLibText){title, "2D local problem as kergs -fclib_input read it (a global one as W = H^T M^-1 H, q = H^T M^-1 f + w)",
                               "W as kergs solved it: the source's upper triangle, mirrored; solution r: the impulses kergs's solver found "
                               "(converged or not), u = W r + q"},
                  path));
  PetscCall(PetscFree(all));
  PetscFunctionReturn(0);
}
