/* kergs files: atomic output files, the checks of a run's paths before any work, free space and failed writes
   (include/kergs/files.h). Rank 0 touches the file system; every rank gets the same outcome. */
#include <kergs/files.h>
#include <petscviewerhdf5.h>
#include <petsclayouthdf5.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

/* Longest message a collective check broadcasts. */
#define KERGS_FILE_MSG (2 * PETSC_MAX_PATH_LEN + 512)

/* Broadcast rank 0's message; a non-empty one becomes the same error on every rank. */
static PetscErrorCode RaiseFromRoot(MPI_Comm comm, PetscErrorCode code, char msg[], int len)
{
  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Bcast(msg, len, MPI_CHAR, 0, comm));
  PetscCheck(msg[0] == 0, comm, code, "%s", msg);
  PetscFunctionReturn(0);
}

/* The directory part of path ("." when it has none), into dir. */
static void DirName(const char path[], char dir[], size_t len)
{
  const char *slash = strrchr(path, '/');

  if (!slash)
    snprintf(dir, len, ".");
  else if (slash == path)
    snprintf(dir, len, "/");
  else
    snprintf(dir, len, "%.*s", (int)(slash - path), path);
}

/* The deepest existing ancestor of dir (dir itself when it exists), into anc; *isdir tells whether it is a directory. */
static void ExistingAncestor(const char dir[], char anc[], size_t len, PetscBool *isdir)
{
  struct stat st;

  snprintf(anc, len, "%s", dir);
  while (stat(anc, &st)) {
    char *slash = strrchr(anc, '/');
    if (!slash) {
      snprintf(anc, len, ".");
      break;
    }
    if (slash == anc)
      slash[1] = 0;
    else
      *slash = 0;
  }
  *isdir = (PetscBool)(!stat(anc, &st) && S_ISDIR(st.st_mode));
}

/* Bytes free for this process on the file system of path (its deepest existing directory); -1 when unknown. */
static double FreeBytes(const char path[])
{
  char           dir[PETSC_MAX_PATH_LEN], anc[PETSC_MAX_PATH_LEN];
  struct statvfs sv;
  PetscBool      isdir;

  DirName(path, dir, sizeof(dir));
  ExistingAncestor(dir, anc, sizeof(anc), &isdir);
  if (statvfs(anc, &sv)) return -1;
  return (double)sv.f_bavail * (double)sv.f_frsize;
}

/* mkdir -p of the directory part of path (rank 0 only); the message is empty on success. */
static void MakeDirectories(const char path[], char msg[], size_t len)
{
  char dir[PETSC_MAX_PATH_LEN];

  msg[0] = 0;
  if (strlen(path) >= sizeof(dir)) {
    snprintf(msg, len, "Output path %s is too long", path);
    return;
  }
  strcpy(dir, path);
  {
    char *slash = strrchr(dir, '/');
    if (!slash || slash == dir) return; /* in the current directory, or directly under / */
    *slash = 0;
  }
  for (char *p = dir + 1;; p++) {
    const char saved = *p;
    if (saved != '/' && saved != 0) continue;
    *p = 0;
    if (mkdir(dir, 0777) && errno != EEXIST) {
      snprintf(msg, len, "Cannot create directory %s for output file %s: %s", dir, path, strerror(errno));
      return;
    }
    *p = saved;
    if (!saved) break;
  }
  {
    struct stat st;
    if (stat(dir, &st) || !S_ISDIR(st.st_mode))
      snprintf(msg, len, "Cannot use %s as the directory of output file %s: not a directory", dir, path);
  }
}

/* Rank 0, when an output is opened: neither it nor its .tmp may be anything but a regular file (checked before the
   run, again here: the file system may have changed since). */
static void CheckReplaceable(const char path[], char msg[], size_t len)
{
  char tmp[PETSC_MAX_PATH_LEN + 8], why[PETSC_MAX_PATH_LEN + 160];

  snprintf(tmp, sizeof(tmp), "%s.tmp", path);
  if (!KergsFileReplaceable(path, why, sizeof(why)) || !KergsFileReplaceable(tmp, why, sizeof(why)))
    snprintf(msg, len, "Output file %s", why);
}

PetscErrorCode KergsFileMakeParentDir(MPI_Comm comm, const char path[])
{
  char        msg[KERGS_FILE_MSG] = "";
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) MakeDirectories(path, msg, sizeof(msg));
  if (rank == 0 && !msg[0]) CheckReplaceable(path, msg, sizeof(msg));
  PetscCall(RaiseFromRoot(comm, PETSC_ERR_FILE_OPEN, msg, (int)sizeof(msg)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFileCommit(MPI_Comm comm, const char tmp[], const char path[])
{
  char        msg[KERGS_FILE_MSG] = "";
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Barrier(comm)); /* every rank has closed its handle on tmp */
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    char why[PETSC_MAX_PATH_LEN + 160];
    if (!KergsFileReplaceable(path, why, sizeof(why))) /* it became one while the run went on: keep the .tmp */
      snprintf(msg, sizeof(msg), "Cannot rename %s to %s: %s (the results stay in %s)", tmp, path, why, tmp);
    else if (rename(tmp, path))
      snprintf(msg, sizeof(msg), "Cannot rename %s to %s: %s", tmp, path, strerror(errno));
  }
  PetscCall(RaiseFromRoot(comm, PETSC_ERR_FILE_WRITE, msg, (int)sizeof(msg)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFileExists(MPI_Comm comm, const char path[], PetscBool *exists)
{
  PetscMPIInt rank;
  int         found = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    struct stat st;
    found = !stat(path, &st);
  }
  PetscCallMPI(MPI_Bcast(&found, 1, MPI_INT, 0, comm));
  *exists = found ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* Rank 0: copy src to dst in blocks; the message is empty on success (a partial dst is removed). */
static void CopyFile(const char src[], const char dst[], char msg[], size_t len)
{
  static char buf[1 << 20];
  FILE       *in = fopen(src, "rb"), *out;
  size_t      n;

  msg[0] = 0;
  if (!in) {
    snprintf(msg, len, "Cannot read %s: %s", src, strerror(errno));
    return;
  }
  out = fopen(dst, "wb");
  if (!out) {
    snprintf(msg, len, "Cannot create %s: %s", dst, strerror(errno));
    fclose(in);
    return;
  }
  while ((n = fread(buf, 1, sizeof(buf), in)) > 0)
    if (fwrite(buf, 1, n, out) != n) break;
  if (ferror(in))
    snprintf(msg, len, "Cannot read %s: %s", src, strerror(errno));
  else if (ferror(out) || fflush(out))
    snprintf(msg, len, "Cannot write %s: %s", dst, strerror(errno));
  fclose(in);
  if (fclose(out) && !msg[0]) snprintf(msg, len, "Cannot write %s: %s", dst, strerror(errno));
  if (msg[0]) (void)remove(dst);
}

PetscErrorCode KergsFileCopy(MPI_Comm comm, const char src[], const char dst[])
{
  char        msg[KERGS_FILE_MSG] = "";
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) CopyFile(src, dst, msg, sizeof(msg));
  PetscCall(RaiseFromRoot(comm, PETSC_ERR_FILE_WRITE, msg, (int)sizeof(msg)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFileCheckSpace(MPI_Comm comm, const char path[], const char tmp[], const char what[], PetscReal bytes)
{
  char        msg[KERGS_FILE_MSG] = "";
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    const double avail = FreeBytes(path);
    if (avail >= 0 && avail < (double)bytes) {
      if (tmp) (void)remove(tmp);
      snprintf(msg, sizeof(msg), "No space left on device: %s of %s needs about %.0f bytes, %.0f are free on its file system%s%s%s", what,
               path, (double)bytes, avail, tmp ? "; the partial " : "", tmp ? tmp : "", tmp ? " was removed" : "");
    }
  }
  PetscCall(RaiseFromRoot(comm, PETSC_ERR_FILE_WRITE, msg, (int)sizeof(msg)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFileWriteFailed(const char path[], const char tmp[], const char what[])
{
  const double avail = FreeBytes(path);

  PetscFunctionBeginUser;
  if (tmp) (void)remove(tmp);
  /* HDF5 and MPI-IO say "file write failed" and keep errno to themselves: a full file system is told by its free space */
  PetscCheck(!(avail >= 0 && avail < 1048576.0), PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE,
             "No space left on device: %s of %s failed with %.0f bytes free on its file system; the partial %s was removed", what, path,
             avail, tmp ? tmp : path);
  SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot write %s of %s (HDF5 write failed, %.0f bytes free); the partial %s was removed",
          what, path, avail, tmp ? tmp : path);
}

/* ------------------------------------------------------------------------------------------------ */
/* Checks of a run's paths                                                                          */

/* Appends to the absolute path `at` (no trailing '/') the components of `rest`, lexically: "." and empty ones are
   skipped, ".." drops the last component. Only for directories that do not exist yet (mkdir -p creates them), which
   hold no links, so that the lexical and the real path agree. */
static void AppendNormalised(char at[], size_t len, const char rest[])
{
  const char *p = rest;

  while (*p) {
    const char *end = strchr(p, '/');
    size_t      n   = end ? (size_t)(end - p) : strlen(p);
    if (n == 2 && !strncmp(p, "..", 2)) {
      char *slash = strrchr(at, '/');
      if (slash) *slash = 0;
    } else if (n && !(n == 1 && p[0] == '.')) {
      size_t na = strlen(at);
      snprintf(at + na, len - na, "/%.*s", (int)n, p);
    }
    p += n + (end ? 1 : 0);
  }
}

/* The directory entry that writing path (by rename) replaces, links resolved: realpath of the deepest existing
   ancestor of its directory, then the directories still to be created (normalised: newdir/../a.h5 is ./a.h5), then
   the base name. */
static void EntryOf(const char path[], char entry[], size_t len)
{
  char        dir[PETSC_MAX_PATH_LEN], anc[PETSC_MAX_PATH_LEN], real[PATH_MAX + PETSC_MAX_PATH_LEN];
  const char *base = strrchr(path, '/'), *rest = "";
  PetscBool   isdir;
  size_t      na;

  base = base ? base + 1 : path;
  DirName(path, dir, sizeof(dir));
  ExistingAncestor(dir, anc, sizeof(anc), &isdir);
  na = strlen(anc);
  if (!realpath(anc, real)) snprintf(real, sizeof(real), "%s", anc);
  if (!strcmp(real, "/")) real[0] = 0; /* entries are joined with '/' below */
  if (strcmp(anc, dir))                /* anc is "." for a relative dir none of which exists */
    rest = !strncmp(dir, anc, na) && (dir[na] == '/' || anc[na - 1] == '/') ? dir + na : dir;
  AppendNormalised(real, sizeof(real), rest);
  snprintf(entry, len, "%s/%s", real, base);
}

PetscBool KergsFileReplaceable(const char path[], char msg[], size_t len)
{
  struct stat st;

  if (stat(path, &st) || S_ISREG(st.st_mode)) return PETSC_TRUE;
  snprintf(msg, len, "%s is %s, not a regular file: kergs would replace it; choose a file name", path,
           S_ISDIR(st.st_mode)    ? "a directory"
           : S_ISCHR(st.st_mode)  ? "a character device"
           : S_ISBLK(st.st_mode)  ? "a block device"
           : S_ISFIFO(st.st_mode) ? "a named pipe"
           : S_ISSOCK(st.st_mode) ? "a socket"
                                  : "a special file");
  return PETSC_FALSE;
}

typedef struct {
  const char *option, *path;
  char        entry[PETSC_MAX_PATH_LEN + 16], tmpentry[PETSC_MAX_PATH_LEN + 16], real[PATH_MAX];
} Named;

/* Rank 0: the checks of one output; the message is empty when it passes. */
static void CheckOutput(const Named *o, char msg[], size_t len)
{
  char        dir[PETSC_MAX_PATH_LEN], anc[PETSC_MAX_PATH_LEN], probe[PETSC_MAX_PATH_LEN + 64], tmp[PETSC_MAX_PATH_LEN + 8];
  char        why[PETSC_MAX_PATH_LEN + 160];
  size_t      n = strlen(o->path);
  struct stat st;
  PetscBool   isdir;
  int         fd;

  msg[0] = 0;
  if (n + 8 >= PETSC_MAX_PATH_LEN) {
    snprintf(msg, len, "Output %s %s is too long (at most %d characters)", o->option, o->path, PETSC_MAX_PATH_LEN - 9);
    return;
  }
  snprintf(tmp, sizeof(tmp), "%s.tmp", o->path);
  if (o->path[n - 1] == '/' || (!stat(o->path, &st) && S_ISDIR(st.st_mode))) {
    snprintf(msg, len, "Output %s %s is a directory: give a file name", o->option, o->path);
    return;
  }
  if (!stat(tmp, &st) && S_ISDIR(st.st_mode)) {
    snprintf(msg, len, "Output %s %s cannot be written: its temporary file %s is a directory", o->option, o->path, tmp);
    return;
  }
  if (!KergsFileReplaceable(o->path, why, sizeof(why)) || !KergsFileReplaceable(tmp, why, sizeof(why))) {
    snprintf(msg, len, "Output %s: %s", o->option, why);
    return;
  }
  DirName(o->path, dir, sizeof(dir));
  ExistingAncestor(dir, anc, sizeof(anc), &isdir);
  if (!isdir) {
    snprintf(msg, len, "Output %s %s cannot be written: %s is not a directory", o->option, o->path, anc);
    return;
  }
  {
    const char  *base  = strrchr(o->path, '/');
    const long   limit = pathconf(anc, _PC_NAME_MAX); /* 255 on Linux's file systems */
    const size_t nb    = strlen(base ? base + 1 : o->path);
    if (limit > 0 && nb + 4 > (size_t)limit) {
      snprintf(msg, len,
               "Output %s %s: its file name has %zu characters, and %s.tmp (written first, then renamed) would exceed the %ld of the file "
               "system in %s: choose a shorter name",
               o->option, o->path, nb, base ? base + 1 : o->path, limit, anc);
      return;
    }
  }
  /* permissions, read-only file systems, quotas on inodes: create and remove a file where the output will go */
  snprintf(probe, sizeof(probe), "%s/.kergs-probe-%ld", anc, (long)getpid());
  fd = open(probe, O_CREAT | O_EXCL | O_WRONLY, 0600);
  if (fd < 0) {
    snprintf(msg, len, "Output %s %s cannot be written: cannot create files in %s: %s", o->option, o->path, anc, strerror(errno));
    return;
  }
  close(fd);
  (void)unlink(probe);
}

static PetscBool SameEntry(const char a[], const char b[]) { return a[0] && !strcmp(a, b) ? PETSC_TRUE : PETSC_FALSE; }

static PetscBool Allowed(const char *out, const char *in, PetscInt nsame, const char *const same[][2])
{
  for (PetscInt k = 0; k < nsame; k++)
    if (!strcmp(same[k][0], out) && !strcmp(same[k][1], in)) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* Rank 0: every check; the message is empty when all pass. */
static void CheckPaths(PetscInt nout, Named out[], PetscInt nin, Named in[], PetscInt nsame, const char *const same[][2], char msg[],
                       size_t len)
{
  msg[0] = 0;
  for (PetscInt i = 0; i < nout; i++) {
    CheckOutput(&out[i], msg, len);
    if (msg[0]) return;
    EntryOf(out[i].path, out[i].entry, sizeof(out[i].entry));
    snprintf(out[i].tmpentry, sizeof(out[i].tmpentry), "%s.tmp", out[i].entry);
  }
  for (PetscInt j = 0; j < nin; j++) {
    EntryOf(in[j].path, in[j].entry, sizeof(in[j].entry));
    if (!realpath(in[j].path, in[j].real)) in[j].real[0] = 0; /* a missing input: its reader says so */
  }
  for (PetscInt i = 0; i < nout; i++) {
    for (PetscInt j = 0; j < nin; j++) {
      const PetscBool clash = (PetscBool)(SameEntry(out[i].entry, in[j].entry) || SameEntry(out[i].entry, in[j].real) ||
                                          SameEntry(out[i].tmpentry, in[j].entry) || SameEntry(out[i].tmpentry, in[j].real));
      if (clash && !Allowed(out[i].option, in[j].option, nsame, same)) {
        snprintf(msg, len, "Output %s %s is the input %s %s (links resolved): writing it would replace the input; choose another file",
                 out[i].option, out[i].path, in[j].option, in[j].path);
        return;
      }
    }
    for (PetscInt k = 0; k < i; k++)
      if (SameEntry(out[i].entry, out[k].entry) || SameEntry(out[i].entry, out[k].tmpentry) || SameEntry(out[i].tmpentry, out[k].entry)) {
        snprintf(msg, len, "Outputs %s %s and %s %s are the same file (links resolved, .tmp files included): give each its own",
                 out[k].option, out[k].path, out[i].option, out[i].path);
        return;
      }
  }
}

PetscErrorCode KergsFileCheckPaths(MPI_Comm comm, PetscInt nout, const KergsFileRole outputs[], PetscInt nin, const KergsFileRole inputs[],
                                   PetscInt nsame, const char *const same[][2])
{
  char        msg[KERGS_FILE_MSG] = "";
  PetscMPIInt rank;
  Named      *out, *in;
  PetscInt    no = 0, ni = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    PetscCall(PetscCalloc2(nout + 1, &out, nin + 1, &in));
    for (PetscInt i = 0; i < nout; i++)
      if (outputs[i].path && outputs[i].path[0]) {
        out[no].option = outputs[i].option;
        out[no++].path = outputs[i].path;
      }
    for (PetscInt j = 0; j < nin; j++)
      if (inputs[j].path && inputs[j].path[0]) {
        in[ni].option = inputs[j].option;
        in[ni++].path = inputs[j].path;
      }
    CheckPaths(no, out, ni, in, nsame, same, msg, sizeof(msg));
    PetscCall(PetscFree2(out, in));
  }
  PetscCall(RaiseFromRoot(comm, PETSC_ERR_FILE_OPEN, msg, (int)sizeof(msg)));
  PetscFunctionReturn(0);
}

static PetscErrorCode AddViewerFile(const char option[], const char value[], void *ctx)
{
  static const char *types[] = {"", "ascii", "binary", "hdf5", "vtk", "matlab"};
  KergsViewerFiles  *vf      = (KergsViewerFiles *)ctx;
  const char        *colon   = strchr(value, ':');
  char               file[PETSC_MAX_PATH_LEN];
  size_t             len;
  PetscBool          known = PETSC_FALSE;

  PetscFunctionBeginUser;
  if (!colon) PetscFunctionReturn(0);
  for (size_t t = 0; t < sizeof(types) / sizeof(types[0]); t++)
    if (strlen(types[t]) == (size_t)(colon - value) && !strncmp(value, types[t], (size_t)(colon - value))) known = PETSC_TRUE;
  len = strcspn(colon + 1, ":");
  if (!known || len == 0 || len >= sizeof(file)) PetscFunctionReturn(0);
  memcpy(file, colon + 1, len);
  file[len] = 0;
  if (!strcmp(file, "stdout") || !strcmp(file, "stderr")) PetscFunctionReturn(0);
  for (PetscInt k = 0; k < vf->n; k++)
    if (!strcmp(vf->path[k], file)) PetscFunctionReturn(0);
  if (vf->n == KERGS_MAX_VIEWER_FILES) PetscFunctionReturn(0);
  snprintf(vf->option[vf->n], sizeof(vf->option[0]), "%s", option);
  snprintf(vf->path[vf->n++], sizeof(vf->path[0]), "%s", file);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFileViewerFiles(KergsViewerFiles *vf)
{
  char *all;

  PetscFunctionBeginUser;
  vf->n = 0;
  PetscCall(PetscOptionsGetAll(NULL, &all));
  PetscCall(KergsOptionsTextWalk(all, AddViewerFile, vf));
  PetscCall(PetscFree(all));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Options files                                                                                    */

#define KERGS_OPTIONS_FILE_DEPTH 32 /* deeper nesting than anyone writes by hand: a cycle by another name */

typedef struct {
  char                    chain[KERGS_OPTIONS_FILE_DEPTH][PATH_MAX]; /* the files being read, outermost first */
  int                     depth;
  KergsOptionsFileVisitor visit;
  void                   *ctx;
} OptionsWalk;

static int WalkOptionsFile(OptionsWalk *w, const char path[], char msg[], size_t len);

/* The -options_file arguments in one file's text, as PETSc reads it: '#' starts a comment to the end of the line, the
   value may be on the next line. */
static int WalkOptionsText(OptionsWalk *w, FILE *fp, char msg[], size_t len)
{
  char     *line = NULL;
  size_t    cap  = 0;
  PetscBool want = PETSC_FALSE;
  int       bad  = 0;

  while (!bad && getline(&line, &cap, fp) >= 0) {
    char *hash = strchr(line, '#'), *save = NULL;
    if (hash) *hash = 0;
    for (char *tok = strtok_r(line, " \t\r\n", &save); tok; tok = strtok_r(NULL, " \t\r\n", &save)) {
      if (want && (bad = WalkOptionsFile(w, tok, msg, len))) break;
      want = (PetscBool)!strcmp(tok, "-options_file");
    }
  }
  free(line);
  return bad;
}

static int WalkOptionsFile(OptionsWalk *w, const char path[], char msg[], size_t len)
{
  char  real[PATH_MAX];
  FILE *fp;
  int   bad = 0;

  if (!realpath(path, real)) return 0; /* missing: PETSc says so */
  for (int d = 0; d < w->depth; d++) {
    if (strcmp(w->chain[d], real)) continue;
    snprintf(msg, len, "Options file %s includes itself (-options_file", path);
    for (int e = d; e < w->depth; e++) {
      size_t n = strlen(msg);
      snprintf(msg + n, len - n, " %s ->", w->chain[e]);
    }
    {
      size_t n = strlen(msg);
      snprintf(msg + n, len - n, " %s): PETSc would read it forever", real);
    }
    return 1;
  }
  if (w->depth == KERGS_OPTIONS_FILE_DEPTH) {
    snprintf(msg, len, "Options file %s: -options_file nested more than %d deep", path, KERGS_OPTIONS_FILE_DEPTH);
    return 1;
  }
  if (w->visit) w->visit(path, w->ctx);
  fp = fopen(path, "r");
  if (!fp) return 0;
  snprintf(w->chain[w->depth++], PATH_MAX, "%s", real);
  bad = WalkOptionsText(w, fp, msg, len);
  w->depth--;
  fclose(fp);
  return bad;
}

int KergsOptionsFilesWalk(int argc, char **argv, KergsOptionsFileVisitor visit, void *ctx, char msg[], size_t len)
{
  static OptionsWalk w; /* PATH_MAX x depth: not on the stack */

  msg[0]  = 0;
  w.depth = 0;
  w.visit = visit;
  w.ctx   = ctx;
  for (int i = 1; i + 1 < argc; i++)
    if (!strcmp(argv[i], "-options_file") && WalkOptionsFile(&w, argv[i + 1], msg, len)) return 1;
  return 0;
}

void KergsFileAvoidLongPathAbort(void)
{
  /* setenv before MPI_Init: Open MPI reads its MCA parameters from the environment then. Harmless elsewhere. */
  if (!getenv("OMPI_MCA_sharedfp")) (void)setenv("OMPI_MCA_sharedfp", "^lockedfile", 0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Datasets                                                                                         */

/* A Vec of nlocal blocks of bs reals on this rank, named, viewed into the current group, destroyed.
   values holds the nlocal * bs local entries (NULL when nlocal is 0). */
PetscErrorCode KergsViewBlocks(PetscViewer viewer, MPI_Comm comm, const char name[], PetscInt nlocal, PetscInt bs, const PetscReal *values)
{
  Vec          vec;
  PetscScalar *a;

  PetscFunctionBeginUser;
  PetscCall(VecCreate(comm, &vec));
  PetscCall(VecSetSizes(vec, nlocal * bs, PETSC_DETERMINE));
  PetscCall(VecSetBlockSize(vec, bs));
  PetscCall(VecSetType(vec, VECMPI));
  PetscCall(VecGetArray(vec, &a));
  for (PetscInt i = 0; i < nlocal * bs; i++) a[i] = values[i];
  PetscCall(VecRestoreArray(vec, &a));
  PetscCall(PetscObjectSetName((PetscObject)vec, name));
  PetscCall(VecView(vec, viewer));
  PetscCall(VecDestroy(&vec));
  PetscFunctionReturn(0);
}

/* Integer fields are stored as reals (exact up to 2^53). */
PetscErrorCode KergsViewIntegers(PetscViewer viewer, MPI_Comm comm, const char name[], PetscInt nlocal, const PetscInt *values)
{
  PetscReal *r;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(nlocal, &r));
  for (PetscInt i = 0; i < nlocal; i++) r[i] = (PetscReal)values[i];
  PetscCall(KergsViewBlocks(viewer, comm, name, nlocal, 1, r));
  PetscCall(PetscFree(r));
  PetscFunctionReturn(0);
}

/* Readers of KergsViewBlocks' datasets (kergs/files.h). */
PetscErrorCode KergsLoadBlocks(PetscViewer v, MPI_Comm comm, const char path[], const char group[], const char name[], PetscInt nglobal,
                               PetscInt bs, PetscInt *nlocal, PetscReal **local)
{
  Vec                vec;
  PetscInt           fbs, fN, n, start, bad = PETSC_MAX_INT; /* the first entry that is not finite */
  const PetscScalar *a;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5ReadSizes(v, name, &fbs, &fN));
  PetscCheck(fN == nglobal * bs, comm, PETSC_ERR_FILE_UNEXPECTED,
             "File %s: dataset %s/%s holds %" PetscInt_FMT " values, expected %" PetscInt_FMT " x %" PetscInt_FMT, path, group, name, fN,
             nglobal, bs);
  n = *nlocal;
  if (n == PETSC_DECIDE) PetscCall(PetscSplitOwnership(comm, &n, &nglobal));
  *nlocal = n;
  PetscCall(PetscMalloc1(n * bs + 1, local));
  if (nglobal == 0) PetscFunctionReturn(0); /* an empty dataset: nothing to load */
  PetscCall(VecCreate(comm, &vec));
  PetscCall(VecSetSizes(vec, n * bs, nglobal * bs));
  PetscCall(VecSetBlockSize(vec, bs));
  PetscCall(VecSetType(vec, VECMPI));
  PetscCall(PetscObjectSetName((PetscObject)vec, name));
  PetscCall(VecLoad(vec, v));
  PetscCall(VecGetOwnershipRange(vec, &start, NULL));
  PetscCall(VecGetArrayRead(vec, &a));
  for (PetscInt i = 0; i < n * bs; i++) {
    (*local)[i] = PetscRealPart(a[i]);
    if (bad == PETSC_MAX_INT && PetscIsInfOrNanReal((*local)[i])) bad = start + i;
  }
  PetscCall(VecRestoreArrayRead(vec, &a));
  PetscCall(VecDestroy(&vec));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT, MPI_MIN, comm));
  PetscCheck(bad == PETSC_MAX_INT, comm, PETSC_ERR_FILE_UNEXPECTED,
             "File %s: dataset %s/%s holds a value that is not finite (entry %" PetscInt_FMT ", block %" PetscInt_FMT ")", path, group,
             name, bad, bad / bs);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsLoadAllBlocks(PetscViewer v, MPI_Comm comm, const char path[], const char group[], const char name[], PetscInt nglobal,
                                  PetscInt bs, PetscReal **all)
{
  PetscInt    n = PETSC_DECIDE;
  PetscReal  *mine;
  PetscMPIInt size, *rc, *displs, nm;

  PetscFunctionBeginUser;
  PetscCall(KergsLoadBlocks(v, comm, path, group, name, nglobal, bs, &n, &mine));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscMalloc2(size, &rc, size, &displs));
  nm = (PetscMPIInt)(n * bs);
  PetscCallMPI(MPI_Allgather(&nm, 1, MPI_INT, rc, 1, MPI_INT, comm));
  displs[0] = 0;
  for (PetscMPIInt q = 1; q < size; q++) displs[q] = displs[q - 1] + rc[q - 1];
  PetscCall(PetscMalloc1(nglobal * bs + 1, all));
  PetscCallMPI(MPI_Allgatherv(mine, nm, MPIU_REAL, *all, rc, displs, MPIU_REAL, comm));
  PetscCall(PetscFree(mine));
  PetscCall(PetscFree2(rc, displs));
  PetscFunctionReturn(0);
}
