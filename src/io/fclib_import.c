/* kergs FCLib import (-fclib_input): a 2D FCLib problem, local (W, q, mu) or global (M, H, f, w, mu), read with Debian's
   libfclib and turned into the local problem kergs's solvers take: u = W r + q, W symmetric.

   libfclib exits the process on an HDF5 failure (a missing dataset, a file that is not HDF5), so rank 0 first checks the
   file with kergs's own HDF5: readable, HDF5, an /fclib_local or /fclib_global group, every dataset libfclib reads
   present with the size it expects, spacedim 2. libfclib is loaded with dlopen as for the export (src/io/fclib_export.c),
   so that its HDF5 calls bind to its own serial HDF5. */
#include <kergs/fclib.h>
#include <kergs/private/h5probe.h>
#include <petscviewerhdf5.h>
#include <errno.h>
#include <string.h>
#include <unistd.h>
#include <fclib.h>

#define KERGS_FCLIB_MSG (2 * PETSC_MAX_PATH_LEN + 256)

typedef struct fclib_local *(*FCLibReadLocalFn)(const char *);
typedef struct fclib_global *(*FCLibReadGlobalFn)(const char *);
typedef struct fclib_solution *(*FCLibReadSolutionFn)(const char *);
typedef void (*FCLibDeleteLocalFn)(struct fclib_local *);
typedef void (*FCLibDeleteGlobalFn)(struct fclib_global *);
typedef void (*FCLibDeleteSolutionsFn)(struct fclib_solution *, int);

/* Number of entries of dataset `name` of file f, -1 when it does not exist (every link of its path is tested: H5Lexists
   fails on a missing intermediate group). */
static long long ImportDatasetSize(hid_t f, const char name[])
{
  char      part[256];
  long long n = -1;
  hid_t     d, sp;

  for (const char *s = strchr(name, '/'); s; s = strchr(s + 1, '/')) {
    snprintf(part, sizeof(part), "%.*s", (int)(s - name), name);
    if (H5Lexists(f, part, H5P_DEFAULT) <= 0) return -1;
  }
  if (H5Lexists(f, name, H5P_DEFAULT) <= 0) return -1;
  if ((d = H5Dopen2(f, name, H5P_DEFAULT)) < 0) return -1;
  if ((sp = H5Dget_space(d)) >= 0) {
    n = (long long)H5Sget_simple_extent_npoints(sp);
    H5Sclose(sp);
  }
  H5Dclose(d);
  return n;
}

/* The first integer of dataset `name` (which exists); 0 when it cannot be read. */
static int ImportReadInt(hid_t f, const char name[])
{
  int   v[1] = {0};
  hid_t d    = H5Dopen2(f, name, H5P_DEFAULT);
  if (d < 0) return 0;
  if (ImportDatasetSize(f, name) == 1) (void)H5Dread(d, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v);
  H5Dclose(d);
  return v[0];
}

/* A matrix group of an FCLib file (prefix/{m,n,nz,nzmax,p,i,x}): every dataset present and of the size libfclib reads. */
static void ImportCheckMatrix(hid_t f, const char path[], const char prefix[], int *m, int *n, char msg[], size_t len)
{
  const char *names[] = {"m", "n", "nz", "nzmax", "p", "i", "x"};
  char        name[128];
  long long   size[7];
  int         nz, nzmax;

  for (int k = 0; k < 7 && !msg[0]; k++) {
    snprintf(name, sizeof(name), "%s/%s", prefix, names[k]);
    size[k] = ImportDatasetSize(f, name);
    if (size[k] < 0)
      snprintf(msg, len, "%s: missing dataset %s (not a complete FCLib problem)", path, name);
    else if (k < 4 && size[k] != 1)
      snprintf(msg, len, "%s: dataset %s has %lld entries, expected 1", path, name, size[k]);
  }
  if (msg[0]) return;
  snprintf(name, sizeof(name), "%s/m", prefix);
  *m = ImportReadInt(f, name);
  snprintf(name, sizeof(name), "%s/n", prefix);
  *n = ImportReadInt(f, name);
  snprintf(name, sizeof(name), "%s/nz", prefix);
  nz = ImportReadInt(f, name);
  snprintf(name, sizeof(name), "%s/nzmax", prefix);
  nzmax = ImportReadInt(f, name);
  if (*m < 0 || *n < 0 || nzmax < 0 || nz < -2 || nz > nzmax)
    snprintf(msg, len, "%s: %s has m %d, n %d, nz %d, nzmax %d: not a valid sparse matrix", path, prefix, *m, *n, nz, nzmax);
  else if (size[4] != (nz == -1 ? *n + 1LL : nz == -2 ? *m + 1LL : nzmax))
    snprintf(msg, len, "%s: %s/p has %lld entries, expected %lld", path, prefix, size[4],
             nz == -1   ? *n + 1LL
             : nz == -2 ? *m + 1LL
                        : (long long)nzmax);
  else if (size[5] != nzmax || size[6] != nzmax)
    snprintf(msg, len, "%s: %s/i and x have %lld and %lld entries, expected nzmax = %d", path, prefix, size[5], size[6], nzmax);
}

/* A vector dataset of the expected size. */
static void ImportCheckVector(hid_t f, const char path[], const char name[], long long expected, char msg[], size_t len)
{
  long long n = ImportDatasetSize(f, name);
  if (msg[0]) return;
  if (n < 0)
    snprintf(msg, len, "%s: missing dataset %s (not a complete FCLib problem)", path, name);
  else if (n != expected)
    snprintf(msg, len, "%s: dataset %s has %lld entries, expected %lld", path, name, n, expected);
}

/* Rank 0, before libfclib sees the file: what it holds (global or local), whether a solution comes with it; msg says why
   the file cannot be read. */
static void ImportCheckFile(const char path[], PetscBool *global, PetscBool *solution, char msg[], size_t len)
{
  KergsH5Quiet quiet;
  hid_t        f;
  int          m = 0, n = 0, spacedim;
  const char  *g;

  if (access(path, R_OK)) {
    snprintf(msg, len, "Cannot read the FCLib file %s: %s", path, strerror(errno));
    return;
  }
  KergsH5QuietBegin(&quiet); /* kergs says what is wrong, not HDF5's trace */
  if (H5Fis_hdf5(path) <= 0 || (f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT)) < 0) {
    snprintf(msg, len, "%s is not an HDF5 file, hence not an FCLib problem", path);
    KergsH5QuietEnd(&quiet);
    return;
  }
  *global = (PetscBool)(H5Lexists(f, "fclib_local", H5P_DEFAULT) <= 0 && H5Lexists(f, "fclib_global", H5P_DEFAULT) > 0);
  g       = *global ? "fclib_global" : "fclib_local";
  if (H5Lexists(f, g, H5P_DEFAULT) <= 0)
    snprintf(msg, len, "%s is an HDF5 file but not an FCLib problem (no /fclib_local nor /fclib_global group)", path);
  if (!msg[0]) {
    char name[64];
    snprintf(name, sizeof(name), "%s/spacedim", g);
    if (ImportDatasetSize(f, name) != 1)
      snprintf(msg, len, "%s: missing dataset %s (not a complete FCLib problem)", path, name);
    else if ((spacedim = ImportReadInt(f, name)) != 2)
      snprintf(msg, len, "%s holds a %dD problem (spacedim %d): kergs solves 2D FCLib problems (spacedim 2) only", path, spacedim,
               spacedim);
  }
  if (!msg[0] && !*global) {
    ImportCheckMatrix(f, path, "fclib_local/W", &m, &n, msg, len);
    if (!msg[0] && (m != n || m % 2)) snprintf(msg, len, "%s: W is %d x %d, expected square with 2 rows per contact", path, m, n);
    ImportCheckVector(f, path, "fclib_local/vectors/q", m, msg, len);
    ImportCheckVector(f, path, "fclib_local/vectors/mu", m / 2, msg, len);
  }
  if (!msg[0] && *global) {
    int mM = 0, nM = 0;
    ImportCheckMatrix(f, path, "fclib_global/M", &mM, &nM, msg, len);
    if (!msg[0]) ImportCheckMatrix(f, path, "fclib_global/H", &n, &m, msg, len);
    if (!msg[0] && (mM != nM || mM != n || m % 2))
      snprintf(msg, len, "%s: M is %d x %d and H %d x %d: expected M n x n, H n x 2 n_c", path, mM, nM, n, m);
    if (!msg[0] && H5Lexists(f, "fclib_global/G", H5P_DEFAULT) > 0)
      snprintf(msg, len, "%s: the global problem has equality constraints (G): kergs solves problems without them", path);
    ImportCheckVector(f, path, "fclib_global/vectors/f", n, msg, len);
    ImportCheckVector(f, path, "fclib_global/vectors/w", m, msg, len);
    ImportCheckVector(f, path, "fclib_global/vectors/mu", m / 2, msg, len);
  }
  *solution = PETSC_FALSE;
  if (!msg[0] && ImportDatasetSize(f, "solution/r") == m && ImportDatasetSize(f, "solution/u") == m) *solution = PETSC_TRUE;
  H5Fclose(f);
  KergsH5QuietEnd(&quiet);
}

/* Triplets of an FCLib matrix (compressed columns nz = -1, compressed rows nz = -2, or nz triplets), checked. */
static PetscErrorCode ImportTriplets(const struct fclib_matrix *A, const char path[], const char what[], PetscInt *nt, PetscInt **ti,
                                     PetscInt **tj, PetscReal **tv, char msg[], size_t len)
{
  const int outer = A->nz == -1 ? A->n : A->m;
  PetscInt  k     = 0;

  PetscFunctionBeginUser;
  *nt = A->nz >= 0 ? A->nz : (A->nz == -1 ? A->p[A->n] : A->p[A->m]);
  if (A->nz < 0)
    for (int o = 0; o < outer && !msg[0]; o++)
      if (A->p[o] < 0 || A->p[o] > A->p[o + 1] || A->p[o + 1] > A->nzmax)
        snprintf(msg, len, "%s: %s's pointers p are not increasing within [0, nzmax]", path, what);
  if (msg[0] || *nt < 0 || *nt > A->nzmax) {
    if (!msg[0]) snprintf(msg, len, "%s: %s has %" PetscInt_FMT " entries, more than nzmax %d", path, what, *nt, A->nzmax);
    *nt = 0;
  }
  PetscCall(PetscMalloc3(PetscMax(*nt, 1), ti, PetscMax(*nt, 1), tj, PetscMax(*nt, 1), tv));
  if (msg[0]) PetscFunctionReturn(0);
  if (A->nz >= 0)
    for (k = 0; k < *nt; k++) (*ti)[k] = A->i[k], (*tj)[k] = A->p[k], (*tv)[k] = A->x[k];
  else
    for (int o = 0; o < outer; o++)
      for (int e = A->p[o]; e < A->p[o + 1]; e++, k++) {
        (*ti)[k] = A->nz == -1 ? A->i[e] : o;
        (*tj)[k] = A->nz == -1 ? o : A->i[e];
        (*tv)[k] = A->x[e];
      }
  for (k = 0; k < *nt && !msg[0]; k++) {
    if ((*ti)[k] < 0 || (*ti)[k] >= A->m || (*tj)[k] < 0 || (*tj)[k] >= A->n)
      snprintf(msg, len, "%s: %s has an entry (%" PetscInt_FMT ", %" PetscInt_FMT ") outside its %d x %d", path, what, (*ti)[k], (*tj)[k],
               A->m, A->n);
    else if (PetscIsInfOrNanReal((*tv)[k]))
      snprintf(msg, len, "%s: %s has a non-finite entry %g at (%" PetscInt_FMT ", %" PetscInt_FMT ")", path, what, (double)(*tv)[k],
               (*ti)[k], (*tj)[k]);
  }
  PetscFunctionReturn(0);
}

/* Compressed rows (sorted columns, duplicates summed) of an m-row matrix from nt triplets. */
static PetscErrorCode ImportCompress(PetscInt m, PetscInt nt, const PetscInt ti[], const PetscInt tj[], const PetscReal tv[],
                                     KergsFCLibProblem *p)
{
  PetscInt *next;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(m + 1, &p->rowptr));
  PetscCall(PetscMalloc2(PetscMax(nt, 1), &p->colind, PetscMax(nt, 1), &p->val));
  PetscCall(PetscMalloc1(m + 1, &next));
  for (PetscInt k = 0; k < nt; k++) p->rowptr[ti[k] + 1]++;
  for (PetscInt i = 0; i < m; i++) p->rowptr[i + 1] += p->rowptr[i];
  for (PetscInt i = 0; i <= m; i++) next[i] = p->rowptr[i];
  for (PetscInt k = 0; k < nt; k++) {
    p->colind[next[ti[k]]] = tj[k];
    p->val[next[ti[k]]++]  = tv[k];
  }
  p->nnz = 0;
  for (PetscInt i = 0; i < m; i++) { /* sort each row, sum duplicates, compact in place */
    const PetscInt lo = p->rowptr[i], hi = p->rowptr[i + 1];
    PetscCall(PetscSortIntWithScalarArray(hi - lo, p->colind + lo, p->val + lo));
    p->rowptr[i] = p->nnz;
    for (PetscInt e = lo; e < hi; e++) {
      if (p->nnz > p->rowptr[i] && p->colind[p->nnz - 1] == p->colind[e])
        p->val[p->nnz - 1] += p->val[e];
      else {
        p->colind[p->nnz] = p->colind[e];
        p->val[p->nnz++]  = p->val[e];
      }
    }
  }
  p->rowptr[m] = p->nnz;
  PetscCall(PetscFree(next));
  PetscFunctionReturn(0);
}

/* W symmetric (relative to its largest entry): the solvers store its upper block triangle only. */
static void ImportCheckSymmetric(const KergsFCLibProblem *p, const char path[], char msg[], size_t len)
{
  PetscReal wmax = 0.0;

  for (PetscInt e = 0; e < p->nnz; e++) wmax = PetscMax(wmax, PetscAbsReal(p->val[e]));
  for (PetscInt i = 0; i < p->m && !msg[0]; i++)
    for (PetscInt e = p->rowptr[i]; e < p->rowptr[i + 1] && !msg[0]; e++) {
      const PetscInt j = p->colind[e];
      PetscReal      t = 0.0; /* W_ji */
      PetscInt       loc;
      if (PetscFindInt(i, p->rowptr[j + 1] - p->rowptr[j], p->colind + p->rowptr[j], &loc), loc >= 0) t = p->val[p->rowptr[j] + loc];
      if (PetscAbsReal(t - p->val[e]) > 1e-10 * wmax)
        snprintf(msg, len,
                 "%s: W is not symmetric (W_%" PetscInt_FMT ",%" PetscInt_FMT " = %g, W_%" PetscInt_FMT ",%" PetscInt_FMT
                 " = %g): kergs's solvers need a symmetric W",
                 path, i, j, (double)p->val[e], j, i, (double)t);
    }
}

/* Rank 0: the local problem of a local FCLib file. */
static PetscErrorCode ImportLocal(const struct fclib_local *L, const char path[], KergsFCLibProblem *p, char msg[], size_t len)
{
  PetscInt   nt, *ti, *tj;
  PetscReal *tv;

  PetscFunctionBeginUser;
  p->m         = L->W->m;
  p->ncontacts = p->m / 2;
  PetscCall(ImportTriplets(L->W, path, "W", &nt, &ti, &tj, &tv, msg, len));
  if (!msg[0]) PetscCall(ImportCompress(p->m, nt, ti, tj, tv, p));
  PetscCall(PetscFree3(ti, tj, tv));
  PetscCall(PetscMalloc2(PetscMax(p->m, 1), &p->q, PetscMax(p->ncontacts, 1), &p->mu));
  for (PetscInt i = 0; i < p->m; i++) p->q[i] = L->q[i];
  for (PetscInt a = 0; a < p->ncontacts; a++) p->mu[a] = L->mu[a];
  PetscFunctionReturn(0);
}

/* Rank 0: the local problem of a global FCLib file, W = H^T M^-1 H, q = H^T M^-1 f + w, for a diagonal M (kergs's mass
   matrices are). Every degree of freedom k adds H_ki H_kj / M_kk to W_ij for each pair (i, j) of its row of H. */
static PetscErrorCode ImportGlobal(const struct fclib_global *G, const char path[], KergsFCLibProblem *p, char msg[], size_t len)
{
  PetscInt   nM, nH, *Mi, *Mj, *Hi, *Hj, *hcol, *hptr, *next, n = G->M->m, nt = 0, *ti, *tj;
  PetscReal *Mv, *Hv, *minv, *hval, *tv;

  PetscFunctionBeginUser;
  p->m         = G->H->n;
  p->ncontacts = p->m / 2;
  p->global    = PETSC_TRUE;
  PetscCall(PetscMalloc2(PetscMax(p->m, 1), &p->q, PetscMax(p->ncontacts, 1), &p->mu));
  for (PetscInt a = 0; a < p->ncontacts; a++) p->mu[a] = G->mu[a];
  for (PetscInt i = 0; i < p->m; i++) p->q[i] = G->w[i];
  PetscCall(ImportTriplets(G->M, path, "M", &nM, &Mi, &Mj, &Mv, msg, len));
  PetscCall(ImportTriplets(G->H, path, "H", &nH, &Hi, &Hj, &Hv, msg, len));
  PetscCall(PetscCalloc2(n + 1, &minv, n + 1, &hptr));
  for (PetscInt k = 0; k < nM && !msg[0]; k++) {
    if (Mi[k] != Mj[k] && Mv[k] != 0.0)
      snprintf(msg, len,
               "%s: M has an off-diagonal entry at (%" PetscInt_FMT ", %" PetscInt_FMT "): kergs reads global problems with a diagonal M",
               path, Mi[k], Mj[k]);
    else if (Mi[k] == Mj[k])
      minv[Mi[k]] += Mv[k];
  }
  for (PetscInt k = 0; k < n && !msg[0]; k++) {
    if (!(minv[k] > 0.0))
      snprintf(msg, len, "%s: M_%" PetscInt_FMT ",%" PetscInt_FMT " = %g: M must be positive definite", path, k, k, (double)minv[k]);
    minv[k] = 1.0 / minv[k];
  }
  /* H by rows: the columns hcol[hptr[k] .. hptr[k+1]) of DOF k, and their values */
  PetscCall(PetscMalloc3(PetscMax(nH, 1), &hcol, PetscMax(nH, 1), &hval, n + 1, &next));
  for (PetscInt k = 0; k < nH && !msg[0]; k++) hptr[Hi[k] + 1]++;
  for (PetscInt k = 0; k < n; k++) hptr[k + 1] += hptr[k];
  for (PetscInt k = 0; k <= n; k++) next[k] = hptr[k];
  for (PetscInt k = 0; k < nH && !msg[0]; k++) {
    hcol[next[Hi[k]]]   = Hj[k];
    hval[next[Hi[k]]++] = Hv[k];
  }
  for (PetscInt k = 0; k < n && !msg[0]; k++) nt += (hptr[k + 1] - hptr[k]) * (hptr[k + 1] - hptr[k]);
  PetscCall(PetscMalloc3(PetscMax(nt, 1), &ti, PetscMax(nt, 1), &tj, PetscMax(nt, 1), &tv));
  nt = 0;
  for (PetscInt k = 0; k < n && !msg[0]; k++)
    for (PetscInt a = hptr[k]; a < hptr[k + 1]; a++) {
      p->q[hcol[a]] += hval[a] * minv[k] * G->f[k];
      for (PetscInt b = hptr[k]; b < hptr[k + 1]; b++) {
        ti[nt]   = hcol[a];
        tj[nt]   = hcol[b];
        tv[nt++] = hval[a] * minv[k] * hval[b];
      }
    }
  if (!msg[0]) PetscCall(ImportCompress(p->m, nt, ti, tj, tv, p));
  PetscCall(PetscFree3(ti, tj, tv));
  PetscCall(PetscFree3(hcol, hval, next));
  PetscCall(PetscFree2(minv, hptr));
  PetscCall(PetscFree3(Mi, Mj, Mv));
  PetscCall(PetscFree3(Hi, Hj, Hv));
  PetscFunctionReturn(0);
}

/* Rank 0: read with libfclib (after ImportCheckFile), then check the values. */
static PetscErrorCode ImportRead(const char path[], KergsFCLibProblem *p, char msg[], size_t len)
{
  PetscBool global = PETSC_FALSE, solution = PETSC_FALSE;

  PetscFunctionBeginUser;
  ImportCheckFile(path, &global, &solution, msg, len);
  if (msg[0]) PetscFunctionReturn(0);
  if (global) {
    FCLibReadGlobalFn    read_global   = NULL;
    FCLibDeleteGlobalFn  delete_global = NULL;
    struct fclib_global *G;
    KergsFCLibSymbol("fclib_read_global", (void **)&read_global, msg, len);
    if (!msg[0]) KergsFCLibSymbol("fclib_delete_global", (void **)&delete_global, msg, len);
    if (msg[0]) PetscFunctionReturn(0);
    if (!(G = read_global(path)))
      snprintf(msg, len, "libfclib could not read the global problem of %s", path);
    else {
      PetscCall(ImportGlobal(G, path, p, msg, len));
      if (G->info && G->info->title) PetscCall(PetscStrncpy(p->title, G->info->title, sizeof(p->title)));
      delete_global(G);
    }
  } else {
    FCLibReadLocalFn    read_local   = NULL;
    FCLibDeleteLocalFn  delete_local = NULL;
    struct fclib_local *L;
    KergsFCLibSymbol("fclib_read_local", (void **)&read_local, msg, len);
    if (!msg[0]) KergsFCLibSymbol("fclib_delete_local", (void **)&delete_local, msg, len);
    if (msg[0]) PetscFunctionReturn(0);
    if (!(L = read_local(path)))
      snprintf(msg, len, "libfclib could not read the local problem of %s", path);
    else {
      PetscCall(ImportLocal(L, path, p, msg, len));
      if (L->info && L->info->title) PetscCall(PetscStrncpy(p->title, L->info->title, sizeof(p->title)));
      delete_local(L);
    }
  }
  for (PetscInt i = 0; i < p->m && !msg[0]; i++)
    if (PetscIsInfOrNanReal(p->q[i])) snprintf(msg, len, "%s: q has a non-finite entry %g at %" PetscInt_FMT, path, (double)p->q[i], i);
  for (PetscInt a = 0; a < p->ncontacts && !msg[0]; a++)
    if (!(p->mu[a] >= 0.0 && p->mu[a] < PETSC_INFINITY))
      snprintf(msg, len, "%s: friction coefficient mu of contact %" PetscInt_FMT " is %g", path, a, (double)p->mu[a]);
  if (!msg[0]) ImportCheckSymmetric(p, path, msg, len);
  if (!msg[0] && solution) {
    FCLibReadSolutionFn    read_solution    = NULL;
    FCLibDeleteSolutionsFn delete_solutions = NULL;
    struct fclib_solution *S;
    KergsFCLibSymbol("fclib_read_solution", (void **)&read_solution, msg, len);
    if (!msg[0]) KergsFCLibSymbol("fclib_delete_solutions", (void **)&delete_solutions, msg, len);
    if (!msg[0] && (S = read_solution(path))) {
      PetscCall(PetscMalloc1(PetscMax(p->m, 1), &p->r_ref));
      for (PetscInt i = 0; i < p->m; i++) p->r_ref[i] = S->r[i];
      delete_solutions(S, 1);
    }
  }
  PetscFunctionReturn(0);
}

/* Every rank: the problem read on rank 0 (allocated here on the other ranks). */
static PetscErrorCode ImportBroadcast(MPI_Comm comm, KergsFCLibProblem *p)
{
  PetscMPIInt rank;
  PetscInt    head[5] = {p->ncontacts, p->m, p->nnz, p->r_ref ? 1 : 0, p->global};

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Bcast(head, 5, MPIU_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(p->title, sizeof(p->title), MPI_CHAR, 0, comm));
  if (rank) {
    p->ncontacts = head[0];
    p->m         = head[1];
    p->nnz       = head[2];
    p->global    = (PetscBool)head[4];
    PetscCall(PetscMalloc1(p->m + 1, &p->rowptr));
    PetscCall(PetscMalloc2(PetscMax(p->nnz, 1), &p->colind, PetscMax(p->nnz, 1), &p->val));
    PetscCall(PetscMalloc2(PetscMax(p->m, 1), &p->q, PetscMax(p->ncontacts, 1), &p->mu));
    if (head[3]) PetscCall(PetscMalloc1(PetscMax(p->m, 1), &p->r_ref));
  }
  PetscCallMPI(MPI_Bcast(p->rowptr, (PetscMPIInt)(p->m + 1), MPIU_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(p->colind, (PetscMPIInt)p->nnz, MPIU_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(p->val, (PetscMPIInt)p->nnz, MPIU_REAL, 0, comm));
  PetscCallMPI(MPI_Bcast(p->q, (PetscMPIInt)p->m, MPIU_REAL, 0, comm));
  PetscCallMPI(MPI_Bcast(p->mu, (PetscMPIInt)p->ncontacts, MPIU_REAL, 0, comm));
  if (head[3]) PetscCallMPI(MPI_Bcast(p->r_ref, (PetscMPIInt)p->m, MPIU_REAL, 0, comm));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibRead(MPI_Comm comm, const char path[], KergsFCLibProblem *p)
{
  PetscMPIInt rank;
  char        msg[KERGS_FCLIB_MSG] = "";

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscMemzero(p, sizeof(*p)));
  PetscCheck(path && path[0], comm, PETSC_ERR_ARG_WRONG, "-fclib_input: empty file name");
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) PetscCall(ImportRead(path, p, msg, sizeof(msg)));
  PetscCallMPI(MPI_Bcast(msg, (int)sizeof(msg), MPI_CHAR, 0, comm));
  if (msg[0]) PetscCall(KergsFCLibProblemFree(p));
  PetscCheck(msg[0] == 0, comm, PETSC_ERR_FILE_UNEXPECTED, "FCLib input: %s", msg);
  PetscCheck(p->m < PETSC_MPI_INT_MAX, comm, PETSC_ERR_SUP, "FCLib input %s: %" PetscInt_FMT " unknowns do not fit an MPI count", path,
             p->m);
  PetscCall(ImportBroadcast(comm, p));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFCLibProblemFree(KergsFCLibProblem *p)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(p->rowptr));
  PetscCall(PetscFree2(p->colind, p->val));
  PetscCall(PetscFree2(p->q, p->mu));
  PetscCall(PetscFree(p->r_ref));
  PetscFunctionReturn(0);
}
