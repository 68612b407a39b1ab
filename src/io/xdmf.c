/* kergs XDMF: the Xdmf 2 description of a results file's snapshots, for ParaView (include/kergs/xdmf.h,
   docs/results.md). Every array is a reference into the HDF5 file; written to <path>.tmp, then renamed. */
#include <kergs/xdmf.h>
#include <kergs/files.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>

PetscErrorCode KergsXdmfPath(const char results[], char xdmf[], size_t len)
{
  size_t n = strlen(results);

  PetscFunctionBeginUser;
  if (n >= 3 && !strcmp(results + n - 3, ".h5")) n -= 3;
  PetscCheck(n + 6 <= len && n < (size_t)INT_MAX, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "The XDMF path of %s is too long", results);
  PetscCall(PetscSNPrintf(xdmf, len, "%.*s.xdmf", (int)n, results));
  PetscFunctionReturn(0);
}

/* s with the characters XML reserves replaced by entities. */
static void XmlEscape(const char s[], char out[], size_t len)
{
  size_t k = 0;

  for (; *s && k + 7 < len; s++) {
    const char *e = *s == '&' ? "&amp;" : *s == '<' ? "&lt;" : *s == '>' ? "&gt;" : *s == '"' ? "&quot;" : NULL;
    if (e) {
      memcpy(out + k, e, strlen(e));
      k += strlen(e);
    } else
      out[k++] = *s;
  }
  out[k] = 0;
}

/* A reference to dataset `name` of the snapshot group `group`, of shape `dims` (text: "n 2"). */
static void XdmfData(FILE *fp, const char h5[], const char group[], const char name[], const char dims[])
{
  fprintf(fp, "<DataItem Dimensions=\"%s\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:%s/%s</DataItem>", dims, h5, group, name);
}

/* An attribute from a whole dataset (columns: 1 scalar, 2 a vector). */
static void XdmfAttribute(FILE *fp, const char h5[], const char group[], const char name[], const char label[], const char center[],
                          PetscInt rows, PetscInt columns)
{
  char dims[64];

  if (columns == 1)
    snprintf(dims, sizeof(dims), "%" PetscInt_FMT, rows);
  else
    snprintf(dims, sizeof(dims), "%" PetscInt_FMT " %" PetscInt_FMT, rows, columns);
  fprintf(fp, "    <Attribute Name=\"%s\" AttributeType=\"%s\" Center=\"%s\">", label, columns == 1 ? "Scalar" : "Vector", center);
  XdmfData(fp, h5, group, name, dims);
  fprintf(fp, "</Attribute>\n");
}

/* A cell attribute from column `col` of the (rows, 2) dataset `name` (a hyperslab: start, stride, count). */
static void XdmfColumn(FILE *fp, const char h5[], const char group[], const char name[], const char label[], PetscInt rows, PetscInt col)
{
  char dims[64];

  snprintf(dims, sizeof(dims), "%" PetscInt_FMT " 2", rows);
  fprintf(fp, "    <Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Cell\">\n", label);
  fprintf(fp, "      <DataItem ItemType=\"HyperSlab\" Dimensions=\"%" PetscInt_FMT " 1\" Type=\"HyperSlab\">\n", rows);
  fprintf(fp, "       <DataItem Dimensions=\"3 2\" Format=\"XML\">0 %" PetscInt_FMT " 1 1 %" PetscInt_FMT " 1</DataItem>\n       ", col,
          rows);
  XdmfData(fp, h5, group, name, dims);
  fprintf(fp, "\n      </DataItem>\n     </Attribute>\n");
}

/* The opening of the uniform grid of one snapshot in a temporal collection: its name and time. */
static void XdmfGridBegin(FILE *fp, const KergsXdmfSnapshot *s)
{
  fprintf(fp, "   <Grid Name=\"step %" PetscInt_FMT "\" GridType=\"Uniform\">\n    <Time Value=\"%.17g\"/>\n", s->step, (double)s->time);
}

/* n lines (2 nodes each) whose endpoints are the rows of dataset `name` (n, 4): a_x a_y b_x b_y; the Xdmf 2 reader
   takes the 4n values as 2n points and joins points 2k and 2k + 1. Without lines the grid keeps its place with one
   point and no cell (the reader cannot read an empty dataset). PETSC_FALSE when there is no line (no attribute then). */
static PetscBool XdmfLines(FILE *fp, const char h5[], const char group[], const char name[], PetscInt n)
{
  char dims[64];

  fprintf(fp, "    <Topology TopologyType=\"Polyline\" NumberOfElements=\"%" PetscInt_FMT "\" NodesPerElement=\"2\"/>\n", n);
  if (n == 0) {
    fprintf(fp, "    <Geometry GeometryType=\"XY\"><DataItem Dimensions=\"1 2\" Format=\"XML\">0 0</DataItem></Geometry>\n");
    return PETSC_FALSE;
  }
  snprintf(dims, sizeof(dims), "%" PetscInt_FMT " 4", n);
  fprintf(fp, "    <Geometry GeometryType=\"XY\">");
  XdmfData(fp, h5, group, name, dims);
  fprintf(fp, "</Geometry>\n");
  return PETSC_TRUE;
}

/* The disks of snapshot k: n points, one single-point cell each, and their fields. */
static void XdmfDisks(FILE *fp, const char h5[], const char group[], const KergsXdmfSnapshot *s)
{
  const PetscInt n = s->ndisks;
  char           dims[64];

  XdmfGridBegin(fp, s);
  fprintf(fp, "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%" PetscInt_FMT "\" NodesPerElement=\"1\"/>\n", n);
  if (n == 0)
    fprintf(fp, "    <Geometry GeometryType=\"XY\"><DataItem Dimensions=\"1 2\" Format=\"XML\">0 0</DataItem></Geometry>\n");
  else {
    snprintf(dims, sizeof(dims), "%" PetscInt_FMT " 2", n);
    fprintf(fp, "    <Geometry GeometryType=\"XY\">");
    XdmfData(fp, h5, group, "x", dims);
    fprintf(fp, "</Geometry>\n");
    XdmfAttribute(fp, h5, group, "radius", "radius", "Node", n, 1);
    XdmfAttribute(fp, h5, group, "v", "v", "Node", n, 2);
    XdmfAttribute(fp, h5, group, "omega", "omega", "Node", n, 1);
    XdmfAttribute(fp, h5, group, "rot", "rot", "Node", n, 1);
    XdmfAttribute(fp, h5, group, "id", "id", "Node", n, 1);
    XdmfAttribute(fp, h5, group, "material", "material", "Node", n, 1);
  }
  fprintf(fp, "   </Grid>\n");
}

/* The contacts of snapshot k: m lines (the force-chain segments) with the impulse's columns and the contact's fields. */
static void XdmfContacts(FILE *fp, const char h5[], const char group[], const KergsXdmfSnapshot *s)
{
  const PetscInt m = s->ncontacts;

  XdmfGridBegin(fp, s);
  if (XdmfLines(fp, h5, group, "segment", m)) {
    XdmfColumn(fp, h5, group, "r", "rn", m, 0);
    XdmfColumn(fp, h5, group, "r", "rt", m, 1);
    XdmfAttribute(fp, h5, group, "n", "n", "Cell", m, 2);
    XdmfAttribute(fp, h5, group, "gap", "gap", "Cell", m, 1);
    XdmfAttribute(fp, h5, group, "kind", "kind", "Cell", m, 1);
  }
  fprintf(fp, "   </Grid>\n");
}

/* The walls of snapshot k: w lines. */
static void XdmfWalls(FILE *fp, const char h5[], const char group[], const KergsXdmfSnapshot *s)
{
  XdmfGridBegin(fp, s);
  if (XdmfLines(fp, h5, group, "walls", s->nwalls)) XdmfAttribute(fp, h5, group, "wall_infinite", "infinite", "Cell", s->nwalls, 1);
  fprintf(fp, "   </Grid>\n");
}

/* One temporal collection per kind of object (the reader's blocks disks, contacts, walls, under the same names at every
   time), each listing the snapshots in order. */
static void XdmfBody(FILE *fp, const char h5[], PetscInt n, const KergsXdmfSnapshot snap[])
{
  const char *kinds[3]                                                           = {"disks", "contacts", "walls"};
  void (*grid[3])(FILE *, const char[], const char[], const KergsXdmfSnapshot *) = {XdmfDisks, XdmfContacts, XdmfWalls};
  char group[64];

  for (int j = 0; j < 3; j++) {
    fprintf(fp, "  <Grid Name=\"%s\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", kinds[j]);
    for (PetscInt k = 0; k < n; k++) {
      snprintf(group, sizeof(group), "/snapshots/%06" PetscInt_FMT, k);
      grid[j](fp, h5, group, &snap[k]);
    }
    fprintf(fp, "  </Grid>\n");
  }
}

PetscErrorCode KergsXdmfWrite(const char path[], const char h5file[], PetscInt n, const KergsXdmfSnapshot snap[])
{
  char  tmp[PETSC_MAX_PATH_LEN + 8], h5[3 * PETSC_MAX_PATH_LEN], why[2 * PETSC_MAX_PATH_LEN];
  FILE *fp;
  int   failed, err;

  PetscFunctionBeginUser;
  PetscCheck(!strchr(h5file, ':'), PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "The XDMF file %s cannot reference %s: XDMF separates the file from the dataset with ':'", path, h5file);
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", path));
  XmlEscape(h5file, h5, sizeof(h5));
  PetscCheck(KergsFileReplaceable(path, why, sizeof(why)) && KergsFileReplaceable(tmp, why, sizeof(why)), PETSC_COMM_SELF,
             PETSC_ERR_FILE_OPEN, "XDMF file %s", why);
  fp = fopen(tmp, "w");
  PetscCheck(fp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot create the XDMF file %s: %s", tmp, strerror(errno));
  fprintf(fp, "<?xml version=\"1.0\" ?>\n<!-- kergs results %s as a time series; open it with ParaView's \"XDMF Reader\" -->\n", h5);
  fprintf(fp, "<Xdmf Version=\"2.0\">\n <Domain>\n");
  XdmfBody(fp, h5, n, snap);
  fprintf(fp, " </Domain>\n</Xdmf>\n");
  failed = ferror(fp);
  err    = failed ? errno : 0;
  if (fclose(fp) && !failed) {
    failed = 1;
    err    = errno;
  }
  if (failed) (void)remove(tmp);
  PetscCheck(!failed, PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot write the XDMF file %s: %s; the partial %s was removed", path,
             strerror(err), tmp);
  PetscCheck(KergsFileReplaceable(path, why, sizeof(why)), PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot rename %s to %s: %s", tmp, path,
             why);
  PetscCheck(!rename(tmp, path), PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot rename %s to %s: %s", tmp, path, strerror(errno));
  PetscFunctionReturn(0);
}
