/* Writes small 2D FCLib problems with known exact solutions, through Debian's libfclib (the library kergs's
   exporter uses), for the tests of scripts/siconos_solve.py (tests/siconos.cmake). Standalone: links only
   libfclib and the serial HDF5, not kergs.

   Usage: fclib_samples DIR   writes into DIR:
     known.fclib.h5          6 contacts, exact solution stored in /solution
     wrong.fclib.h5          same problem, stored r violates Coulomb's law at contact 1
     permuted.fclib.h5       same problem and solution, contacts in another order
     altered.fclib.h5        permuted, one coupling W_01 changed by 1e-6 (relative 2.5e-7)
     altered_block.fclib.h5  one coupling entry moved inside its block: same per-contact features, other W
     no_mu.fclib.h5          known without /fclib_local/vectors/mu
     bad_p.fclib.h5          known with /fclib_local/W/p one entry short

   The problem: the solution is chosen first, contact by contact (open, stick, slip, frictionless, two
   identical sticking contacts), then q = u - W r, so u = W r + q holds by construction. Unknowns per
   contact normal then tangential. W is symmetric positive definite: diagonal blocks >= I, small couplings
   of contact 0 (open, r = 0) with the others, so every contact but 0 keeps its one-contact solution. */
#include <fclib.h>
#include <hdf5.h>
#include <hdf5_hl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NC 6
#define M (2 * NC)

typedef struct {
  double W[M][M], q[M], mu[NC], r[M], u[M];
} Sample;

static void SetBlock(Sample *s, int a, int b, double w00, double w01, double w10, double w11)
{
  s->W[2 * a][2 * b]         = w00;
  s->W[2 * a][2 * b + 1]     = w01;
  s->W[2 * a + 1][2 * b]     = w10;
  s->W[2 * a + 1][2 * b + 1] = w11;
  if (a != b) { /* symmetric: W_ba = W_ab^T */
    s->W[2 * b][2 * a]         = w00;
    s->W[2 * b + 1][2 * a]     = w01;
    s->W[2 * b][2 * a + 1]     = w10;
    s->W[2 * b + 1][2 * a + 1] = w11;
  }
}

static void SetContact(Sample *s, int a, double mu, double rn, double rt, double un, double ut)
{
  s->mu[a]        = mu;
  s->r[2 * a]     = rn;
  s->r[2 * a + 1] = rt;
  s->u[2 * a]     = un;
  s->u[2 * a + 1] = ut;
}

/* q = u - W r */
static void ComputeQ(Sample *s)
{
  for (int i = 0; i < M; i++) {
    s->q[i] = s->u[i];
    for (int j = 0; j < M; j++) s->q[i] -= s->W[i][j] * s->r[j];
  }
}

/* u = W r + q (after changing r) */
static void ComputeU(Sample *s)
{
  for (int i = 0; i < M; i++) {
    s->u[i] = s->q[i];
    for (int j = 0; j < M; j++) s->u[i] += s->W[i][j] * s->r[j];
  }
}

static void KnownSample(Sample *s)
{
  memset(s, 0, sizeof(*s));
  SetBlock(s, 0, 0, 4, 0, 0, 4);
  SetBlock(s, 1, 1, 1, 0, 0, 1);
  SetBlock(s, 2, 2, 1, 0, 0, 1);
  SetBlock(s, 3, 3, 2, 0, 0, 2);
  SetBlock(s, 4, 4, 1, 0, 0, 1);
  SetBlock(s, 5, 5, 1, 0, 0, 1);
  SetBlock(s, 0, 1, 0.5, 0.2, 0.1, 0.3);
  SetBlock(s, 0, 2, 0.3, -0.1, 0.2, 0.4);
  SetBlock(s, 0, 4, 0.1, 0, 0, 0);
  SetBlock(s, 0, 5, 0, 0, 0.1, 0);
  SetContact(s, 0, 0.3, 0, 0, 1.0, 0.5);  /* open: r = 0, u_n > 0 */
  SetContact(s, 1, 0.3, 1, -0.1, 0, 0);   /* stick: u = 0, |r_t| < mu r_n */
  SetContact(s, 2, 0.3, 1, -0.3, 0, 0.7); /* slip: u_n = 0, u_t > 0, r_t = -mu r_n */
  SetContact(s, 3, 0.0, 1, 0, 0, 0.7);    /* frictionless: r_t = 0, u_t free */
  SetContact(s, 4, 0.3, 1, 0, 0, 0);      /* 4 and 5: same features, told apart only by W_04, W_05 */
  SetContact(s, 5, 0.3, 1, 0, 0, 0);
  ComputeQ(s);
}

/* contact k of out = contact perm[k] of in */
static void Permute(const Sample *in, const int perm[NC], Sample *out)
{
  for (int a = 0; a < NC; a++) {
    out->mu[a] = in->mu[perm[a]];
    for (int c = 0; c < 2; c++) {
      out->q[2 * a + c] = in->q[2 * perm[a] + c];
      out->r[2 * a + c] = in->r[2 * perm[a] + c];
      out->u[2 * a + c] = in->u[2 * perm[a] + c];
      for (int b = 0; b < NC; b++)
        for (int d = 0; d < 2; d++) out->W[2 * a + c][2 * b + d] = in->W[2 * perm[a] + c][2 * perm[b] + d];
    }
  }
}

/* Compressed columns (FCLib nz = -1) of the nonzero entries, rows increasing inside each column. */
static int WriteSample(const char *dir, const char *name, const Sample *s, const char *title)
{
  int    colptr[M + 1], rowind[M * M], nnz = 0;
  double val[M * M], q[M], mu[NC], r[M], u[M];
  char path[4096], description[] = "scripts/siconos_solve.py test problem", math[] = "W symmetric positive definite; exact solution stored";
  struct fclib_matrix   W;
  struct fclib_info     info;
  struct fclib_local    problem;
  struct fclib_solution solution;

  for (int j = 0; j < M; j++) {
    colptr[j] = nnz;
    for (int i = 0; i < M; i++)
      if (s->W[i][j] != 0.0) {
        rowind[nnz] = i;
        val[nnz++]  = s->W[i][j];
      }
  }
  colptr[M] = nnz;
  memcpy(q, s->q, sizeof(q));
  memcpy(mu, s->mu, sizeof(mu));
  memcpy(r, s->r, sizeof(r));
  memcpy(u, s->u, sizeof(u));
  snprintf(path, sizeof(path), "%s/%s", dir, name);
  remove(path); /* libfclib refuses to add a problem to a file that holds one */
  W        = (struct fclib_matrix){.nzmax = nnz, .m = M, .n = M, .p = colptr, .i = rowind, .x = val, .nz = -1, .info = NULL};
  info     = (struct fclib_info){.title = (char *)title, .description = description, .math_info = math};
  problem  = (struct fclib_local){.W = &W, .V = NULL, .R = NULL, .mu = mu, .q = q, .s = NULL, .spacedim = 2, .info = &info};
  solution = (struct fclib_solution){.v = NULL, .u = u, .r = r, .l = NULL};
  if (!fclib_write_local(&problem, path) || !fclib_write_solution(&solution, path)) {
    fprintf(stderr, "fclib_samples: libfclib could not write %s\n", path);
    return 1;
  }
  printf("fclib_samples: wrote %s (%d contacts, %d nonzeros)\n", path, NC, nnz);
  return 0;
}

/* Damage a written file with the serial HDF5: drop a dataset, or replace it with a shorter one. */
static int Damage(const char *dir, const char *name, const char *dataset, int keep)
{
  char  path[4096];
  hid_t file;
  int   err = 0;

  snprintf(path, sizeof(path), "%s/%s", dir, name);
  file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return 1;
  if (keep >= 0) { /* replace by its first keep entries */
    int     buf[M + 1] = {0};
    hsize_t dims[1]    = {(hsize_t)keep};
    err |= H5LTread_dataset_int(file, dataset, buf) < 0;
    err |= H5Ldelete(file, dataset, H5P_DEFAULT) < 0;
    err |= H5LTmake_dataset_int(file, dataset, 1, dims, buf) < 0;
  } else
    err |= H5Ldelete(file, dataset, H5P_DEFAULT) < 0;
  err |= H5Fclose(file) < 0;
  if (err) fprintf(stderr, "fclib_samples: could not change %s in %s\n", dataset, path);
  return err;
}

int main(int argc, char **argv)
{
  static Sample known, other, tmp;
  const int     perm[NC] = {5, 2, 0, 4, 3, 1};
  int           err      = 0;

  if (argc != 2) {
    fprintf(stderr, "usage: %s DIR\n", argv[0]);
    return 2;
  }
  KnownSample(&known);
  err |= WriteSample(argv[1], "known.fclib.h5", &known, "known solution");

  other      = known;
  other.r[2] = 1.0; /* contact 1: r = (1, -0.5), outside the cone |r_t| <= 0.3 r_n */
  other.r[3] = -0.5;
  ComputeU(&other);
  err |= WriteSample(argv[1], "wrong.fclib.h5", &other, "solution violating Coulomb's law");

  Permute(&known, perm, &other);
  err |= WriteSample(argv[1], "permuted.fclib.h5", &other, "known, contacts permuted");

  tmp = known;
  SetBlock(&tmp, 0, 1, 0.5 + 1e-6, 0.2, 0.1, 0.3);
  Permute(&tmp, perm, &other);
  err |= WriteSample(argv[1], "altered.fclib.h5", &other, "known with W_01 changed by 1e-6");

  other = known;
  SetBlock(&other, 0, 5, 0, 0, 0, 0.1); /* W_05 entry (t, n) moved to (t, t): same sums and maxima */
  err |= WriteSample(argv[1], "altered_block.fclib.h5", &other, "known with one coupling entry moved inside its block");

  err |= WriteSample(argv[1], "no_mu.fclib.h5", &known, "known without mu");
  err |= Damage(argv[1], "no_mu.fclib.h5", "/fclib_local/vectors/mu", -1);
  err |= WriteSample(argv[1], "bad_p.fclib.h5", &known, "known with a short column pointer array");
  err |= Damage(argv[1], "bad_p.fclib.h5", "/fclib_local/W/p", M);
  return err ? 1 : 0;
}
