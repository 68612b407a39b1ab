/* An option that takes a value and is given without one is an error naming it (KergsOptionsCheckValues).

   PETSc's readers treat a name without a value as not given (PetscOptionsGetReal and the others return set = false), so
   "-dt" alone would run with the built-in time step, overriding the options file. PETSc keeps no record of how an
   option is read outside -help: only the help printer knows it, in the line each reader prints ("  -dt <0.001 : 0.001>:
   ..." for a value, "  -quiet: <FALSE : FALSE> ..." for a flag, "  -solver_monitor ascii[..." for a viewer, whose value
   is optional). So, when some option has no value, rank 0 runs the program's readers once with -help, alone
   (PETSC_COMM_SELF) and on a copy of the options database (the run's own keeps its used marks for the unknown-option
   check), records those lines instead of printing them, and every option given without a value that is listed only as
   taking one is an error. The readers' own errors are left to the run's reading, which follows; the objects a failed
   reader built are not freed. */
#include <kergs/base.h>
#include <strings.h>

/* What the readers wrote to standard output while they ran (rank 0's: PETSc prints there only). The help lines come
   through PetscHelpPrintf, or straight through PetscFPrintf for the lists of types (PetscFunctionListPrintTypes); both
   end in PetscVFPrintf, PETSc's hook for all its output, which the check replaces while the readers run. */
static char  *HelpText;
static size_t HelpLength, HelpCapacity;
static PetscErrorCode (*PrintOutput)(FILE *, const char[], va_list);

static PetscErrorCode HelpTextReserve(size_t extra)
{
  PetscFunctionBeginUser;
  if (HelpLength + extra + 1 > HelpCapacity) {
    HelpCapacity = PetscMax(2 * HelpCapacity, HelpLength + extra + 1);
    PetscCall(PetscRealloc(HelpCapacity, &HelpText));
  }
  PetscFunctionReturn(0);
}

/* Replaces PetscVFPrintf while the readers run: standard output is recorded, not printed; the rest (errors, on
   standard error) is printed as usual. */
static PetscErrorCode HelpTextRecord(FILE *fd, const char format[], va_list args)
{
  va_list again;
  size_t  full;

  PetscFunctionBeginUser;
  if (fd != PETSC_STDOUT) {
    PetscCall((*PrintOutput)(fd, format, args));
    PetscFunctionReturn(0);
  }
  PetscCall(HelpTextReserve(256));
  va_copy(again, args);
  PetscCall(PetscVSNPrintf(HelpText + HelpLength, HelpCapacity - HelpLength, format, &full, args));
  if (HelpLength + full + 1 > HelpCapacity) {
    PetscCall(HelpTextReserve(full));
    PetscCall(PetscVSNPrintf(HelpText + HelpLength, HelpCapacity - HelpLength, format, &full, again));
  }
  va_end(again);
  PetscCall(PetscStrlen(HelpText, &HelpLength));
  PetscFunctionReturn(0);
}

/* Options of the PETSc objects the program creates (-predictor_ksp_type, -solver_tresca_tao_monitor, ...): PETSc owns
   their meaning without a value (-tao_monitor alone monitors to stdout). Each object's options start with its class's
   stem after the object's prefix; no option of kergs's own contains one. */
static PetscBool IsPetscObjectOption(const char name[])
{
  static const char *stems[] = {"ksp_", "pc_", "snes_", "tao_", "mat_", NULL};

  for (PetscInt i = 0; stems[i]; i++) {
    size_t n = strlen(stems[i]);
    for (const char *p = name; (p = strstr(p, stems[i])); p += n)
      if (p == name || p[-1] == '_') return PETSC_TRUE;
  }
  return PETSC_FALSE;
}

/* An option given without a value, not of a PETSc object (the caller lists only the options not read yet: PETSc's own,
   -log_view or -malloc_dump, were read at PetscInitialize). */
static PetscBool Unvalued(const char name[], const char value[]) { return !value && !IsPetscObjectOption(name) ? PETSC_TRUE : PETSC_FALSE; }

/* Rank 0 alone: runs read_all on PETSC_COMM_SELF with -help set, on a copy of the options database, recording what it
   prints. The copy leaves out the unvalued options: the help lists every option whether given or not. An error of the
   readers is not reported here (the run's own reading reports it, on every rank): the help printed up to it is used. */
static PetscErrorCode RecordHelp(PetscErrorCode (*read_all)(MPI_Comm, void *), void *ctx, PetscInt n, char **names, char **values)
{
  PetscOptions copy;
  char        *all;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetAll(NULL, &all));
  PetscCall(PetscOptionsCreate(&copy));
  PetscCall(PetscOptionsInsertString(copy, all));
  PetscCall(PetscFree(all));
  for (PetscInt i = 0; i < n; i++) {
    char name[256];
    if (!Unvalued(names[i], values[i])) continue;
    PetscCall(PetscSNPrintf(name, sizeof(name), "-%s", names[i]));
    PetscCall(PetscOptionsClearValue(copy, name));
  }
  PetscCall(PetscOptionsSetValue(copy, "-help", NULL));
  PetscCall(PetscOptionsPush(copy));
  HelpLength = 0;
  PetscCall(HelpTextReserve(0));
  HelpText[0]   = 0;
  PrintOutput   = PetscVFPrintf;
  PetscVFPrintf = HelpTextRecord;
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  (void)(*read_all)(PETSC_COMM_SELF, ctx);
  PetscCall(PetscPopErrorHandler());
  PetscVFPrintf = PrintOutput;
  PetscCall(PetscOptionsPop());
  PetscCall(PetscOptionsDestroy(&copy));
  PetscFunctionReturn(0);
}

/* The line after p in the recorded help, NULL at its end. */
static const char *NextLine(const char *p)
{
  const char *end = strchr(p, '\n');
  return end && end[1] ? end + 1 : NULL;
}

/* How the recorded help lists option `name` (without its dash; names are case-insensitive): *value if some line shows
   it taking a value ("  -name <"), *optional if some line shows it as a flag ("  -name: ") or a viewer
   ("  -name ascii[..."); *line (length *length) is the first line that lists it, NULL if none does. */
static void HelpListing(const char name[], PetscBool *value, PetscBool *optional, const char **line, int *length)
{
  size_t n = strlen(name);

  *value = *optional = PETSC_FALSE;
  *line              = NULL;
  for (const char *p = HelpLength ? HelpText : NULL; p; p = NextLine(p)) {
    if (strncmp(p, "  -", 3) || strncasecmp(p + 3, name, n) || (p[3 + n] != ' ' && p[3 + n] != ':')) continue;
    if (!strncmp(p + 3 + n, " <", 2))
      *value = PETSC_TRUE;
    else
      *optional = PETSC_TRUE;
    if (!*line) {
      const char *end = strchr(p, '\n');
      *line           = p + 2;
      *length         = (int)(end ? (size_t)(end - *line) : strlen(*line));
    }
  }
}

/* Rank 0, on the recorded help: prints each unvalued option listed only as taking a value, with its help line. */
static PetscErrorCode ReportMissingValues(PetscInt n, char **names, char **values, PetscInt *missing, char first[], size_t size)
{
  PetscFunctionBeginUser;
  *missing = 0;
  for (PetscInt i = 0; i < n; i++) {
    PetscBool   value, optional;
    const char *line;
    int         length = 0;

    if (!Unvalued(names[i], values[i])) continue;
    HelpListing(names[i], &value, &optional, &line, &length);
    if (!value || optional) continue;
    PetscCall(PetscPrintf(PETSC_COMM_SELF, "kergs: option -%s is given without its value; kergs -help lists it as\n  %.*s\n", names[i],
                          length, line));
    if (!(*missing)++) PetscCall(PetscStrncpy(first, names[i], size));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOptionsCheckValues(MPI_Comm comm, PetscErrorCode (*read_all)(MPI_Comm, void *), void *ctx)
{
  PetscInt    n, missing = 0;
  char      **names, **values, first[256] = "";
  PetscBool   any = PETSC_FALSE;
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsLeftGet(NULL, &n, &names, &values));
  for (PetscInt i = 0; i < n; i++) any = (PetscBool)(any || Unvalued(names[i], values[i]));
  if (any) { /* the same on every rank: they share the database; rank 0 decides */
    PetscCallMPI(MPI_Comm_rank(comm, &rank));
    if (rank == 0) {
      PetscCall(RecordHelp(read_all, ctx, n, names, values));
      PetscCall(ReportMissingValues(n, names, values, &missing, first, sizeof(first)));
    }
    PetscCallMPI(MPI_Bcast(&missing, 1, MPIU_INT, 0, comm));
    PetscCallMPI(MPI_Bcast(first, sizeof(first), MPI_CHAR, 0, comm));
    PetscCall(PetscFree(HelpText));
    HelpLength = HelpCapacity = 0;
  }
  PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
  PetscCheck(!missing, comm, PETSC_ERR_USER_INPUT,
             "Option -%s needs a value%s: an option given without its value would silently keep its default, overriding the "
             "options file",
             first, missing > 1 ? " (and the others listed above)" : "");
  PetscFunctionReturn(0);
}
