/*
 * What karst does with VTK 9.1 (CommonCore, CommonDataModel, IOXML), in a thin extern "C" shim
 * built as the plugin libkarst_vtk.so (io/vtk_api_internal.h: libkarst opens it on first use,
 * so that a process that never reads a .vtp does not pay VTK's ~20 ms start-up): reading .vtp
 * files, writing .vti images and .pvd collections, and VTK's own writers of the PolyData files
 * that karst writes itself (src/io/write_vtp.c), kept as the reference its test compares with.
 *
 * Formats: "VTK File Formats", VTK User's Guide 11th ed., ch. 19 (XML
 * PolyData .vtp, ImageData .vti, and the ParaView collection .pvd).
 *
 * Every file is written with inline binary (base64, zlib-compressed) data:
 * Debian's ParaView 5.11 (patched expat) reads 0 points from appended-mode
 * files. Files go to a temporary name beside the target and are renamed into
 * place, so a failed or interrupted run never leaves a half-written file.
 *
 * VTK reports errors through vtkOutputWindow (stderr) unless the object that
 * raises them has an ErrorEvent observer; every VTK object we create (and its
 * executive, the XML reader's internal parser and reader) gets an observer
 * that records the message, which becomes the karst error message. Nothing
 * here touches VTK's process-wide state, so two threads may write files at
 * the same time (karst ensemble -j 2).
 *
 * No C++ exception crosses the extern "C" boundary: each entry point catches
 * std::bad_alloc (KARST_ENOMEM) and anything else (KARST_EEXTERNAL).
 */
#include "io/input_internal.h"
#include "karst/arrays.h"
#include "karst/io.h"
#include "karst/palette.h"
#include "karst/version.h"
#include "karst/vtk.h"
#include "io/vtk_api_internal.h"
#include "io/vtp_write_internal.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <ostream>
#include <streambuf>
#include <string>

#include <vtkAbstractArray.h>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkDataCompressor.h>
#include <vtkDataSet.h>
#include <vtkDoubleArray.h>
#include <vtkErrorCode.h>
#include <vtkExecutive.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkIntArray.h>
#include <vtkLZ4DataCompressor.h>
#include <vtkLZMADataCompressor.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTypeInt64Array.h>
#include <vtkXMLDataParser.h>
#include <vtkXMLImageDataWriter.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkZLibDataCompressor.h>

namespace {

/* VTK creates its registry of object factories on the first object made (vtkObjectFactory::Init),
 * with no lock: the first two files of an ensemble's workers, written at once, can both create
 * it, and one copy leaks (LeakSanitizer found it in 1 of about 12 two-thread ensembles under
 * ASan, tests/cli/test_conditioning.sh). Made here, when the plugin is loaded (once, under the
 * loader's pthread_once, before any of its functions can run), it is created once. */
const struct FactoryRegistry {
  FactoryRegistry() { vtkObjectFactory::GetRegisteredFactories(); }
} factory_registry;

/* ------------------------------------------------------------------------ */
/* Error capture                                                             */
/* ------------------------------------------------------------------------ */

/*
 * Records VTK's error and warning events instead of letting VTK print them.
 * VTK formats a message as "ERROR: In FILE, line N\nCLASS (0xADDR): TEXT\n..."
 * and an executive's message only says that its algorithm failed; so the
 * first message of a reader, writer or parser is preferred, and only its
 * first line of TEXT is kept, without object addresses (messages stay
 * reproducible).
 */
class ErrorCatcher : public vtkCommand {
public:
  static ErrorCatcher *New() { return new ErrorCatcher; }
  void Execute(vtkObject *caller, unsigned long event, void *data) override {
    std::string text = clean(static_cast<const char *>(data));
    if (event == vtkCommand::ErrorEvent) {
      const bool exec = caller && caller->IsA("vtkExecutive");
      std::string &slot = exec ? executive_error : first_error;
      if (slot.empty()) slot = text;
      errors++;
    } else if (warnings++ == 0) {
      first_warning = text;
    }
  }
  /** Observe errors and warnings raised by @p obj (NULL is ignored). */
  void watch(vtkObject *obj) {
    if (!obj) return;
    obj->AddObserver(vtkCommand::ErrorEvent, this);
    obj->AddObserver(vtkCommand::WarningEvent, this);
  }
  /** The most useful error message recorded (empty when none). */
  std::string message() const { return first_error.empty() ? executive_error : first_error; }
  int errors = 0, warnings = 0;
  std::string first_warning;

private:
  std::string first_error, executive_error;
  static std::string clean(const char *raw) {
    std::string s = raw ? raw : "";
    if (s.compare(0, 3, "ERR") == 0 || s.compare(0, 4, "Warn") == 0) {
      size_t nl = s.find('\n');
      if (nl != std::string::npos) s.erase(0, nl + 1);
    }
    size_t obj = s.find("): ");
    if (obj != std::string::npos && obj < 80) s.erase(0, obj + 3);
    size_t nl = s.find('\n');
    if (nl != std::string::npos) s.erase(nl);
    /* drop object addresses such as "(0x55cb2cb80fe0)" */
    for (size_t at; (at = s.find("(0x")) != std::string::npos;) {
      size_t close = s.find(')', at);
      if (close == std::string::npos) break;
      size_t from = at > 0 && s[at - 1] == ' ' ? at - 1 : at;
      s.erase(from, close + 1 - from);
    }
    while (!s.empty() && (s.back() == ' ' || s.back() == '\r'))
      s.pop_back();
    return s;
  }
};

/*
 * Words for VTK's error codes (vtkErrorCode.h). vtkErrorCode's own
 * GetStringFromErrorCode lives in CommonMisc, which karst does not link;
 * codes below FirstVTKErrorCode are errno values.
 */
std::string error_code_text(unsigned long code) {
  switch (code) {
  case vtkErrorCode::FileNotFoundError:
    return "file not found";
  case vtkErrorCode::CannotOpenFileError:
    return "cannot open the file";
  case vtkErrorCode::UnrecognizedFileTypeError:
    return "unrecognised file type";
  case vtkErrorCode::PrematureEndOfFileError:
    return "premature end of file";
  case vtkErrorCode::FileFormatError:
    return "file format error";
  case vtkErrorCode::NoFileNameError:
    return "no file name";
  case vtkErrorCode::OutOfDiskSpaceError:
    return "out of disk space";
  default:
    break;
  }
  if (code > 0 && code < vtkErrorCode::FirstVTKErrorCode) return std::strerror((int)code);
  return "VTK error code " + std::to_string(code);
}

/* Field-data string array @p name holding @p n strings. */
vtkSmartPointer<vtkStringArray> string_array(const char *name, int n, const char *const *values) {
  auto a = vtkSmartPointer<vtkStringArray>::New();
  a->SetName(name);
  a->SetNumberOfValues(n);
  for (int i = 0; i < n; i++)
    a->SetValue(i, values[i] ? values[i] : "");
  return a;
}

const char *const tunnel_type_names[] = {
#define KARST_X_NAME(code, name) name,
    KARST_TUNNEL_TYPE_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};
const char *const node_kind_names[] = {
#define KARST_X_NAME(code, name) name,
    KARST_NODE_KIND_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};
const char *const sample_source_names[] = {
#define KARST_X_NAME(code, name) name,
    KARST_SAMPLE_SOURCE_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};

/*
 * The lookup tables a ParaView user needs to read integer codes: which name
 * tunnel_type 0..6 and node kind 0..5 stand for (string-free cell data stays
 * colourable; the names travel beside it).
 */
void add_lookup_tables(vtkFieldData *fd) {
  fd->AddArray(string_array("tunnel_type_names", KARST_TUNNEL_TYPE_COUNT, tunnel_type_names));
  fd->AddArray(string_array("node_kind_names", KARST_NODE_KIND_COUNT, node_kind_names));
}

/* The software that wrote a file: field data "versions", one "name version" string per component
 * (karst_versions), the same list as run.json's "versions" and `karst --version`. */
void add_versions(vtkFieldData *fd) {
  karst_component_t c[KARST_COMPONENTS_MAX];
  const int n = karst_versions(c);
  auto a = vtkSmartPointer<vtkStringArray>::New();
  a->SetName("versions");
  a->SetNumberOfValues(n);
  for (int i = 0; i < n; i++)
    a->SetValue(i, std::string(c[i].name) + " " + c[i].version);
  fd->AddArray(a);
}

/*
 * State in the file what every point and cell array means (include/karst/arrays.h): its unit
 * as VTK's standard information key UNITS_LABEL on the array, and one row (array, unit,
 * meaning) of the 3-component field-data string table "array_units", in the order point
 * arrays, cell arrays. A categorical array also gets the field-data array naming its
 * categories (value i names code i, from include/karst/palette.h) unless the file already
 * has it. An array karst does not describe gets the unit "unknown".
 */
void describe_arrays(vtkDataSet *ds, const char *role) {
  auto table = vtkSmartPointer<vtkStringArray>::New();
  table->SetName("array_units");
  table->SetNumberOfComponents(3);
  table->SetComponentName(0, "array");
  table->SetComponentName(1, "unit");
  table->SetComponentName(2, "meaning");
  vtkFieldData *fd = ds->GetFieldData();
  vtkFieldData *parts[2] = {ds->GetPointData(), ds->GetCellData()};
  for (vtkFieldData *part : parts)
    for (int i = 0; i < part->GetNumberOfArrays(); i++) {
      vtkAbstractArray *a = part->GetAbstractArray(i);
      if (!a || !a->GetName()) continue;
      const karst_array_info_t *info = karst_arrays_find_role(a->GetName(), role);
      const char *unit = info ? info->unit : "unknown";
      table->InsertNextValue(a->GetName());
      table->InsertNextValue(unit);
      table->InsertNextValue(info ? info->meaning : "not described by karst (docs/arrays.md)");
      if (vtkDataArray::SafeDownCast(a))
        a->GetInformation()->Set(vtkDataArray::UNITS_LABEL(), unit);
      const karst_palette_t *pal =
          info && info->names ? karst_palette_find_role(info->name, role) : nullptr;
      if (!pal || fd->GetAbstractArray(info->names)) continue;
      int n = 0; /* codes 0 .. n-1 */
      for (int k = 0; k < pal->n; k++)
        if (pal->categories[k].code >= n) n = pal->categories[k].code + 1;
      if (n == 0) continue; /* only the file knows the names (springs ...) */
      auto names = vtkSmartPointer<vtkStringArray>::New();
      names->SetName(info->names);
      names->SetNumberOfValues(n);
      for (int k = 0; k < pal->n; k++)
        if (pal->categories[k].code >= 0)
          names->SetValue(pal->categories[k].code, pal->categories[k].name);
      fd->AddArray(names);
    }
  fd->AddArray(table);
}

bool finite3(const double *p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

/* Points of a data set, stored as doubles so that coordinates round-trip exactly. */
karst_error_t make_points(karst_ctx_t *ctx, const char *path, const char *what, karst_int_t n,
                          const double *xyz, vtkSmartPointer<vtkPoints> &out) {
  if (n > 0 && !xyz)
    return karst_set_error(ctx, KARST_EINVAL, "%s: %" PRId64 " %s but no coordinates", path, n,
                           what);
  auto pts = vtkSmartPointer<vtkPoints>::New();
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(n);
  for (karst_int_t i = 0; i < n; i++) {
    if (!finite3(xyz + 3 * i))
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: %s %" PRId64 " has a non-finite coordinate (%g, %g, %g)", path,
                             what, i, xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    pts->SetPoint(i, xyz + 3 * i);
  }
  out = pts;
  return KARST_SUCCESS;
}

/*
 * Fixed-size cells (vertices, lines or triangles) from an index list,
 * checking every index against the number of points. A NULL @p idx with
 * size 1 means one vertex cell per point (cell c holds point c).
 */
karst_error_t make_cells(karst_ctx_t *ctx, const char *path, const char *what, int size,
                         karst_int_t n_cells, const karst_int_t *idx, karst_int_t n_points,
                         vtkSmartPointer<vtkCellArray> &out) {
  if (n_cells > 0 && !idx && size != 1)
    return karst_set_error(ctx, KARST_EINVAL, "%s: %" PRId64 " %ss but no indices", path, n_cells,
                           what);
  auto conn = vtkSmartPointer<vtkTypeInt64Array>::New();
  conn->SetNumberOfValues(n_cells * size);
  for (karst_int_t c = 0; c < n_cells; c++)
    for (int k = 0; k < size; k++) {
      karst_int_t v = idx ? idx[(size_t)c * size + k] : c;
      if (v < 0 || v >= n_points)
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: %s %" PRId64 " refers to point %" PRId64
                               ", outside [0, %" PRId64 ")",
                               path, what, c, v, n_points);
      conn->SetValue(c * size + k, v);
    }
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  if (!cells->SetData(size, conn))
    return karst_set_error(ctx, KARST_EEXTERNAL, "%s: VTK refused the %s connectivity", path, what);
  out = cells;
  return KARST_SUCCESS;
}

/* One karst attribute as a VTK array (Int32 for integer attributes, Float64 otherwise). */
karst_error_t make_attr_array(karst_ctx_t *ctx, const char *path, const char *what,
                              const karst_attr_t *a, karst_int_t n,
                              vtkSmartPointer<vtkDataArray> &out) {
  if (a->ncomp < 1 || a->name[0] == '\0' || (n > 0 && !a->data))
    return karst_set_error(ctx, KARST_EINVAL,
                           "%s: %s attribute '%s' is malformed (ncomp %d, data %s)", path, what,
                           a->name, a->ncomp, a->data ? "set" : "NULL");
  const karst_int_t nv = n * a->ncomp;
  if (a->integer) {
    auto arr = vtkSmartPointer<vtkIntArray>::New();
    arr->SetNumberOfComponents(a->ncomp);
    arr->SetNumberOfTuples(n);
    int *dst = arr->GetPointer(0);
    for (karst_int_t i = 0; i < nv; i++) {
      double v = a->data[i];
      if (!(v >= INT32_MIN && v <= INT32_MAX) || v != std::floor(v))
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: %s attribute '%s' is marked integer but %s %" PRId64
                               " has the value %g (not a 32-bit integer)",
                               path, what, a->name, what, i / a->ncomp, v);
      dst[i] = (int)v;
    }
    out = arr;
  } else {
    auto arr = vtkSmartPointer<vtkDoubleArray>::New();
    arr->SetNumberOfComponents(a->ncomp);
    arr->SetNumberOfTuples(n);
    if (nv > 0) std::memcpy(arr->GetPointer(0), a->data, (size_t)nv * sizeof(double));
    out = arr;
  }
  out->SetName(a->name);
  return KARST_SUCCESS;
}

/*
 * The output buffer the XML writers write through. VTK 9.1's
 * vtkXMLUnstructuredDataWriter deletes its position arrays twice when its
 * stream fails in the middle of a piece (a full disk, a quota): karst crashed
 * instead of reporting the error. This buffer never reports a failure to its
 * stream: it writes with pwrite(2) at its own logical position (VTK seeks
 * back to fill in compression headers), keeps the first error (errno), and
 * discards what follows; write_atomically checks it once VTK returns.
 */
class PositionedBuf : public std::streambuf {
public:
  explicit PositionedBuf(int fd) : fd_(fd) { setp(buf_, buf_ + sizeof buf_); }
  /** Write what is buffered; the first error (an errno value), or 0. */
  int finish() {
    drain();
    return err_;
  }

protected:
  int_type overflow(int_type c) override {
    drain();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override {
    drain();
    return 0;
  }
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override {
    drain();
    off_type base = dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? pos_ : end_;
    if (base + off < 0) return pos_type(off_type(-1));
    pos_ = base + off;
    return pos_type(pos_);
  }
  pos_type seekpos(pos_type sp, std::ios_base::openmode which) override {
    return seekoff(off_type(sp), std::ios_base::beg, which);
  }

private:
  void drain() {
    const char *p = pbase();
    size_t n = (size_t)(pptr() - pbase());
    off_t at = (off_t)pos_;
    while (n > 0 && err_ == 0) {
      ssize_t w = pwrite(fd_, p, n, at);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) {
        err_ = w < 0 ? errno : EIO;
        break;
      }
      p += w, n -= (size_t)w, at += w;
    }
    pos_ += pptr() - pbase();
    if (pos_ > end_) end_ = pos_;
    setp(buf_, buf_ + sizeof buf_);
  }
  int fd_;
  int err_ = 0;
  off_type pos_ = 0, end_ = 0;
  char buf_[1 << 16];
};

/* A VTK XML writer that writes to a stream of ours (vtkXMLWriter::Stream is
 * protected; when set, the writer uses it instead of opening FileName). */
template <class W> class StreamedWriter : public W {
public:
  static StreamedWriter *New() {
    StreamedWriter *w = new StreamedWriter;
    w->InitializeObjectBase();
    return w;
  }
  void UseStream(std::ostream *os) { this->Stream = os; }
};

/*
 * Write @p data with @p writer to a temporary name beside @p path, then rename
 * it into place. On any failure no file is left behind and the message names
 * @p path and says what VTK or the system reported.
 */
template <class W>
karst_error_t write_atomically(karst_ctx_t *ctx, const char *path, StreamedWriter<W> *writer,
                               vtkDataObject *data) {
  if (karst_interrupted(ctx))
    return karst_set_error(ctx, KARST_EINTERRUPTED, "%s: interrupted before writing", path);
  char *tmp = karst_temp_name(path);
  if (!tmp) return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path);
  int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) {
    int e = errno;
    std::free(tmp);
    return karst_set_error(ctx, KARST_EIO, "%s: cannot write: %s", path, std::strerror(e));
  }
  karst_error_t err = KARST_SUCCESS;
  {
    PositionedBuf buf(fd);
    std::ostream os(&buf);
    vtkNew<ErrorCatcher> catcher;
    catcher->watch(writer);
    catcher->watch(writer->GetExecutive());
    writer->SetInputData(data);
    writer->SetFileName(tmp);
    writer->UseStream(&os);
    writer->SetDataModeToBinary(); /* inline binary; see the file comment */
    writer->SetCompressorTypeToZLib();
    writer->SetCompressionLevel(KARST_I_VTP_ZLIB_LEVEL);
    writer->SetHeaderTypeToUInt64(); /* arrays larger than 4 GiB stay readable */
    catcher->watch(writer->GetCompressor());
    int ok = writer->Write();
    writer->UseStream(nullptr); /* VTK clears it after a write; do not rely on it */
    int e = buf.finish();
    if (close(fd) != 0 && e == 0) e = errno;
    if (!ok || catcher->errors > 0 || writer->GetErrorCode() != vtkErrorCode::NoError || e != 0) {
      std::string why = e != 0                ? std::string(std::strerror(e))
                        : catcher->errors > 0 ? catcher->message()
                                              : error_code_text(writer->GetErrorCode());
      err = karst_set_error(ctx, KARST_EIO, "%s: cannot write: %s", path, why.c_str());
    } else if (catcher->warnings > 0) {
      karst_log(ctx, KARST_LOG_WARNING, "%s: VTK: %s", path, catcher->first_warning.c_str());
    }
    writer->SetInputData(nullptr);
  }
  if (err)
    std::remove(tmp);
  else
    err = karst_rename_into_place(ctx, tmp, path);
  std::free(tmp);
  return err;
}

karst_error_t check_path(karst_ctx_t *ctx, const char *path) {
  if (!path || !*path) return karst_set_error(ctx, KARST_EINVAL, "no output file name given");
  return KARST_SUCCESS;
}

/* ------------------------------------------------------------------------ */
/* Writers                                                                   */
/* ------------------------------------------------------------------------ */

karst_error_t write_network(karst_ctx_t *ctx, const char *path, const karst_network_t *net) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (!net) return karst_set_error(ctx, KARST_EINVAL, "%s: no network given", path);
  if (net->n_nodes < 0 || net->n_edges < 0)
    return karst_set_error(ctx, KARST_EINVAL,
                           "%s: negative size (%" PRId64 " nodes, %" PRId64 " edges)", path,
                           net->n_nodes, net->n_edges);
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  vtkSmartPointer<vtkPoints> pts;
  if ((err = make_points(ctx, path, "node", net->n_nodes, net->xyz, pts))) return err;
  pd->SetPoints(pts);
  vtkSmartPointer<vtkCellArray> lines;
  if ((err = make_cells(ctx, path, "edge", 2, net->n_edges, net->edges, net->n_nodes, lines)))
    return err;
  pd->SetLines(lines);

  for (int i = 0; i < net->n_node_attrs; i++) {
    const karst_attr_t *a = &net->node_attrs[i];
    if (net->node_labels && std::strcmp(a->name, "label") == 0)
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: node attribute 'label' clashes with the node labels", path);
    vtkSmartPointer<vtkDataArray> arr;
    if ((err = make_attr_array(ctx, path, "node", a, net->n_nodes, arr))) return err;
    pd->GetPointData()->AddArray(arr);
  }
  for (int i = 0; i < net->n_edge_attrs; i++) {
    vtkSmartPointer<vtkDataArray> arr;
    if ((err = make_attr_array(ctx, path, "edge", &net->edge_attrs[i], net->n_edges, arr)))
      return err;
    pd->GetCellData()->AddArray(arr);
  }
  /* ParaView colours by the active scalars when a file is opened. */
  if (karst_network_attr_find(net, KARST_ATTR_EDGE, "tunnel_type"))
    pd->GetCellData()->SetActiveScalars("tunnel_type");
  if (net->node_labels) {
    auto labels = vtkSmartPointer<vtkStringArray>::New();
    labels->SetName("label");
    labels->SetNumberOfValues(net->n_nodes);
    for (karst_int_t i = 0; i < net->n_nodes; i++)
      labels->SetValue(i, net->node_labels[i] ? net->node_labels[i] : "");
    pd->GetPointData()->AddArray(labels);
  }
  vtkFieldData *fd = pd->GetFieldData();
  if (net->crs) fd->AddArray(string_array("crs", 1, &net->crs));
  for (int i = 0; i < net->n_strings; i++)
    fd->AddArray(string_array(net->strings[i].name, net->strings[i].n,
                              (const char *const *)net->strings[i].values));
  if (net->title) fd->AddArray(string_array("title", 1, &net->title));
  add_lookup_tables(fd);
  add_versions(fd);
  describe_arrays(pd, "network");

  vtkNew<StreamedWriter<vtkXMLPolyDataWriter>> writer;
  return write_atomically(ctx, path, writer.GetPointer(), pd);
}

karst_error_t write_samples(karst_ctx_t *ctx, const char *path, const karst_samples_t *s) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (!s) return karst_set_error(ctx, KARST_EINVAL, "%s: no samples given", path);
  if (s->n < 0)
    return karst_set_error(ctx, KARST_EINVAL, "%s: negative sample count %" PRId64, path, s->n);
  if (s->n > 0 && !s->source)
    return karst_set_error(ctx, KARST_EINVAL, "%s: %" PRId64 " samples but no source tags", path,
                           s->n);
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  vtkSmartPointer<vtkPoints> pts;
  if ((err = make_points(ctx, path, "sample", s->n, s->xyz, pts))) return err;
  pd->SetPoints(pts);
  /* One vertex cell per sample, so that ParaView draws them without a glyph filter. */
  vtkSmartPointer<vtkCellArray> verts;
  if ((err = make_cells(ctx, path, "vertex", 1, s->n, nullptr, s->n, verts))) return err;
  pd->SetVerts(verts);
  auto src = vtkSmartPointer<vtkIntArray>::New();
  src->SetName("source");
  src->SetNumberOfValues(s->n);
  for (karst_int_t i = 0; i < s->n; i++) {
    if (s->source[i] >= KARST_SAMPLE_SOURCE_COUNT)
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: sample %" PRId64 " has source %d, outside [0, %d)", path, i,
                             (int)s->source[i], (int)KARST_SAMPLE_SOURCE_COUNT);
    src->SetValue(i, s->source[i]);
  }
  pd->GetPointData()->AddArray(src);
  pd->GetPointData()->SetActiveScalars("source");
  vtkFieldData *fd = pd->GetFieldData();
  fd->AddArray(string_array("source_names", KARST_SAMPLE_SOURCE_COUNT, sample_source_names));
  auto nkey = vtkSmartPointer<vtkTypeInt64Array>::New();
  nkey->SetName("n_key_points");
  nkey->InsertNextValue(s->n_key_points);
  fd->AddArray(nkey);
  if (s->crs) fd->AddArray(string_array("crs", 1, &s->crs));
  add_versions(fd);
  describe_arrays(pd, "samples");

  vtkNew<StreamedWriter<vtkXMLPolyDataWriter>> writer;
  return write_atomically(ctx, path, writer.GetPointer(), pd);
}

karst_error_t write_mesh(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m, int n_extra = 0,
                         const char *const *extra_names = nullptr,
                         const int *const *extra = nullptr) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (!m) return karst_set_error(ctx, KARST_EINVAL, "%s: no mesh given", path);
  if (m->n_vertices < 0 || m->n_triangles < 0)
    return karst_set_error(ctx, KARST_EINVAL,
                           "%s: negative size (%" PRId64 " vertices, %" PRId64 " triangles)", path,
                           m->n_vertices, m->n_triangles);
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  vtkSmartPointer<vtkPoints> pts;
  if ((err = make_points(ctx, path, "vertex", m->n_vertices, m->xyz, pts))) return err;
  pd->SetPoints(pts);
  vtkSmartPointer<vtkCellArray> polys;
  if ((err = make_cells(ctx, path, "triangle", 3, m->n_triangles, m->tri, m->n_vertices, polys)))
    return err;
  pd->SetPolys(polys);
  if (m->tri_label) {
    const char *name = m->tri_label_name && *m->tri_label_name ? m->tri_label_name : "label";
    auto lab = vtkSmartPointer<vtkIntArray>::New();
    lab->SetName(name);
    lab->SetNumberOfValues(m->n_triangles);
    for (karst_int_t t = 0; t < m->n_triangles; t++)
      lab->SetValue(t, m->tri_label[t]);
    pd->GetCellData()->AddArray(lab);
    pd->GetCellData()->SetActiveScalars(name);
  }
  if (m->tri_feature) {
    auto feat = vtkSmartPointer<vtkIntArray>::New();
    feat->SetName("feature");
    feat->SetNumberOfValues(m->n_triangles);
    for (karst_int_t t = 0; t < m->n_triangles; t++)
      feat->SetValue(t, m->tri_feature[t]);
    pd->GetCellData()->AddArray(feat);
  }
  for (int k = 0; k < n_extra; k++) {
    if (!extra_names || !extra_names[k] || !*extra_names[k] || !extra || !extra[k])
      return karst_set_error(ctx, KARST_EINVAL, "%s: cell array %d has no name or no values", path,
                             k);
    auto arr = vtkSmartPointer<vtkIntArray>::New();
    arr->SetName(extra_names[k]);
    arr->SetNumberOfValues(m->n_triangles);
    for (karst_int_t t = 0; t < m->n_triangles; t++)
      arr->SetValue(t, extra[k][t]);
    pd->GetCellData()->AddArray(arr);
    if (!m->tri_label && k == 0) pd->GetCellData()->SetActiveScalars(extra_names[k]);
  }
  add_versions(pd->GetFieldData());
  describe_arrays(pd, "mesh");
  vtkNew<StreamedWriter<vtkXMLPolyDataWriter>> writer;
  return write_atomically(ctx, path, writer.GetPointer(), pd);
}

karst_error_t write_polydata(karst_ctx_t *ctx, const char *path, const karst_polydata_t *m) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (!m || m->n_points < 0 || m->n_polys < 0 || (m->n_polys > 0 && (!m->offsets || !m->conn)))
    return karst_set_error(ctx, KARST_EINVAL, "%s: no polygons given", path);
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  vtkSmartPointer<vtkPoints> pts;
  if ((err = make_points(ctx, path, "point", m->n_points, m->xyz, pts))) return err;
  pd->SetPoints(pts);
  /* offsets and connectivity written at their final size (cell by cell, the arrays' growth and
   * first touch were most of the time of a large geology.vtp) */
  auto offsets = vtkSmartPointer<vtkTypeInt64Array>::New();
  auto conn = vtkSmartPointer<vtkTypeInt64Array>::New();
  offsets->SetNumberOfValues(m->n_polys + 1);
  offsets->SetValue(0, 0);
  karst_int_t n_conn = 0;
  for (karst_int_t c = 0; c < m->n_polys; c++) {
    karst_int_t b = m->offsets[c], e = m->offsets[c + 1];
    if (b < 0 || e < b + 3)
      return karst_set_error(ctx, KARST_EINVAL, "%s: polygon %" PRId64 " has fewer than 3 points",
                             path, c);
    n_conn += e - b;
    offsets->SetValue(c + 1, n_conn);
  }
  conn->SetNumberOfValues(n_conn);
  for (karst_int_t c = 0, k = 0; c < m->n_polys; c++)
    for (karst_int_t i = m->offsets[c]; i < m->offsets[c + 1]; i++, k++) {
      if (m->conn[i] < 0 || m->conn[i] >= m->n_points)
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: polygon %" PRId64 " refers to point %" PRId64 " of %" PRId64,
                               path, c, m->conn[i], m->n_points);
      conn->SetValue(k, m->conn[i]);
    }
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  polys->SetData(offsets, conn);
  pd->SetPolys(polys);
  for (int a = 0; a < m->n_cell_arrays; a++) {
    auto arr = vtkSmartPointer<vtkIntArray>::New();
    arr->SetName(m->cell_array_names[a]);
    arr->SetNumberOfValues(m->n_polys);
    for (karst_int_t c = 0; c < m->n_polys; c++)
      arr->SetValue(c, m->cell_arrays[a][c]);
    pd->GetCellData()->AddArray(arr);
    if (a == 0) pd->GetCellData()->SetActiveScalars(m->cell_array_names[a]);
  }
  for (int i = 0; i < m->n_strings; i++)
    pd->GetFieldData()->AddArray(string_array(m->strings[i].name, m->strings[i].n,
                                              (const char *const *)m->strings[i].values));
  add_versions(pd->GetFieldData());
  describe_arrays(pd, m->role);
  vtkNew<StreamedWriter<vtkXMLPolyDataWriter>> writer;
  return write_atomically(ctx, path, writer.GetPointer(), pd);
}

karst_error_t write_image(karst_ctx_t *ctx, const char *path, const int dims[3],
                          const double origin[3], const double spacing[3], const float *values,
                          const char *name) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (!dims || !origin || !spacing)
    return karst_set_error(ctx, KARST_EINVAL, "%s: grid dimensions, origin or spacing missing",
                           path);
  if (!name || !*name)
    return karst_set_error(ctx, KARST_EINVAL, "%s: the scalar field needs a name", path);
  int64_t n = 1;
  for (int k = 0; k < 3; k++) {
    if (dims[k] < 1)
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: grid dimension %d is %d; each must be at least 1", path, k,
                             dims[k]);
    if (!std::isfinite(origin[k]))
      return karst_set_error(ctx, KARST_EINVAL, "%s: origin[%d] is not finite (%g)", path, k,
                             origin[k]);
    if (!(spacing[k] > 0) || !std::isfinite(spacing[k]))
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: spacing[%d] must be positive and finite, got %g", path, k,
                             spacing[k]);
    n *= dims[k]; /* at most (2^31)^3 / 2^31 per step: no overflow while n < 2^62 */
    if (n > ((int64_t)1 << 40))
      return karst_set_error(ctx, KARST_ERANGE, "%s: grid %d x %d x %d is too large", path, dims[0],
                             dims[1], dims[2]);
  }
  if (!values) return karst_set_error(ctx, KARST_EINVAL, "%s: no grid values given", path);
  auto img = vtkSmartPointer<vtkImageData>::New();
  img->SetDimensions(dims[0], dims[1], dims[2]);
  img->SetOrigin(origin[0], origin[1], origin[2]);
  img->SetSpacing(spacing[0], spacing[1], spacing[2]);
  auto arr = vtkSmartPointer<vtkFloatArray>::New();
  arr->SetName(name);
  /* Borrow the caller's values (save = 1: VTK never frees or writes them) to
   * avoid copying a grid that may hold hundreds of millions of values. */
  arr->SetArray(const_cast<float *>(values), (vtkIdType)n, 1);
  img->GetPointData()->SetScalars(arr);
  add_versions(img->GetFieldData());
  describe_arrays(img, "field");
  vtkNew<StreamedWriter<vtkXMLImageDataWriter>> writer;
  return write_atomically(ctx, path, writer.GetPointer(), img);
}

/* ------------------------------------------------------------------------ */
/* Reader                                                                    */
/* ------------------------------------------------------------------------ */

/* The first value of field-data string array @p name, or NULL when absent or empty. */
const char *field_string(vtkFieldData *fd, const char *name) {
  if (!fd) return nullptr;
  auto *a = vtkStringArray::SafeDownCast(fd->GetAbstractArray(name));
  if (!a || a->GetNumberOfValues() < 1 || a->GetValue(0).empty()) return nullptr;
  return a->GetValue(0).c_str();
}

char *dup_cstr(const char *s) {
  if (!s) return nullptr;
  size_t n = std::strlen(s) + 1;
  char *d = static_cast<char *>(std::malloc(n));
  if (d) std::memcpy(d, s, n);
  return d;
}

/* Whether a VTK array holds whole numbers (any integer or bit type). */
int is_integral(vtkDataArray *a) {
  const int t = a->GetDataType();
  return t != VTK_FLOAT && t != VTK_DOUBLE;
}

/* A name for VTK array @p i of @p what ("point"/"cell"): its own, or "point_array_3". */
std::string array_name(vtkAbstractArray *a, const char *what, int i) {
  const char *n = a->GetName();
  if (n && *n) return n;
  return std::string(what) + "_array_" + std::to_string(i);
}

karst_error_t read_network(karst_ctx_t *ctx, const char *path, karst_network_t *out) {
  karst_error_t err = KARST_SUCCESS;
  if (!path || !*path) return karst_set_error(ctx, KARST_EINVAL, "no input file name given");
  if (!out) return karst_set_error(ctx, KARST_EINVAL, "%s: no network to read into", path);
  /* VTK's XML reader trusts the file's counts and block headers (it allocates
   * what they claim, and some malformed structures crash it): check them
   * against the file first, through the guarded opening of every input. */
  if ((err = karst_i_vtp_check(ctx, path))) return err;
  vtkNew<ErrorCatcher> catcher;
  vtkNew<vtkXMLPolyDataReader> reader;
  catcher->watch(reader);
  catcher->watch(reader->GetExecutive());
  reader->SetReaderErrorObserver(catcher);
  reader->SetParserErrorObserver(catcher);
  if (!reader->CanReadFile(path))
    return karst_set_error(ctx, KARST_EPARSE,
                           "%s: not a VTK XML PolyData file (expected <VTKFile type=\"PolyData\">)",
                           path);
  reader->SetFileName(path);
  /* The header pass creates the XML parser and its decompressor; observe the
   * decompressor too, or zlib errors on damaged data go to stderr. */
  reader->UpdateInformation();
  if (catcher->errors == 0 && reader->GetXMLParser())
    catcher->watch(reader->GetXMLParser()->GetCompressor());
  if (catcher->errors == 0) reader->Update();
  vtkPolyData *pd = reader->GetOutput();
  if (catcher->errors > 0 || reader->GetErrorCode() != vtkErrorCode::NoError || !pd) {
    std::string why =
        catcher->errors > 0 ? catcher->message() : error_code_text(reader->GetErrorCode());
    return karst_set_error(ctx, KARST_EPARSE, "%s: cannot read VTK PolyData: %s", path,
                           why.c_str());
  }
  if (catcher->warnings > 0)
    karst_log(ctx, KARST_LOG_WARNING, "%s: VTK: %s", path, catcher->first_warning.c_str());

  const karst_int_t np = pd->GetNumberOfPoints();
  vtkCellArray *lines = pd->GetLines();
  const karst_int_t nverts = pd->GetNumberOfVerts();
  if (pd->GetNumberOfPolys() > 0 || pd->GetNumberOfStrips() > 0 || nverts > 0)
    karst_log(ctx, KARST_LOG_WARNING,
              "%s: %" PRId64 " vertex, %" PRId64 " polygon and %" PRId64
              " strip cells ignored (only lines become edges)",
              path, nverts, (karst_int_t)pd->GetNumberOfPolys(),
              (karst_int_t)pd->GetNumberOfStrips());

  karst_network_t n;
  karst_network_init(&n);
  /* For each edge, the line cell it comes from (cell data of a polyline is
   * repeated on each of its edges). */
  karst_int_t *edge_cell = nullptr;
  karst_int_t edge_cell_cap = 0;
  for (karst_int_t i = 0; i < np; i++) {
    double p[3];
    pd->GetPoint(i, p);
    if (!finite3(p)) {
      err =
          karst_set_error(ctx, KARST_EPARSE,
                          "%s: Points: point %" PRId64 " has a non-finite coordinate (%g, %g, %g)",
                          path, i, p[0], p[1], p[2]);
      goto cleanup;
    }
    if ((err = karst_network_add_node(&n, p[0], p[1], p[2], nullptr))) goto nomem;
  }
  if (lines) {
    auto it = vtk::TakeSmartPointer(lines->NewIterator());
    karst_int_t cell = 0;
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell(), cell++) {
      vtkIdType sz;
      const vtkIdType *ids;
      it->GetCurrentCell(sz, ids);
      for (vtkIdType k = 0; k < sz; k++)
        if (ids[k] < 0 || ids[k] >= np) {
          err = karst_set_error(ctx, KARST_EPARSE,
                                "%s: line %" PRId64 " refers to point %" PRId64
                                ", outside [0, %" PRId64 ")",
                                path, cell, (karst_int_t)ids[k], np);
          goto cleanup;
        }
      for (vtkIdType k = 0; k + 1 < sz; k++) {
        karst_int_t e;
        if ((err = karst_network_add_edge(&n, ids[k], ids[k + 1], &e))) goto nomem;
        if (e >= edge_cell_cap) {
          karst_int_t cap = edge_cell_cap ? 2 * edge_cell_cap : 64;
          auto *ec = static_cast<karst_int_t *>(
              std::realloc(edge_cell, (size_t)cap * sizeof(karst_int_t)));
          if (!ec) goto nomem;
          edge_cell = ec;
          edge_cell_cap = cap;
        }
        edge_cell[e] = nverts + cell; /* cell ids run verts, lines, polys, strips */
      }
    }
  }

  for (int dom = 0; dom < 2; dom++) {
    vtkDataSetAttributes *attrs =
        dom == 0 ? static_cast<vtkDataSetAttributes *>(pd->GetPointData()) : pd->GetCellData();
    const char *what = dom == 0 ? "point" : "cell";
    const karst_int_t need = dom == 0 ? np : pd->GetNumberOfCells();
    const karst_int_t count = dom == 0 ? n.n_nodes : n.n_edges;
    for (int i = 0; i < attrs->GetNumberOfArrays(); i++) {
      vtkAbstractArray *aa = attrs->GetAbstractArray(i);
      if (!aa) continue;
      std::string name = array_name(aa, what, i);
      if (aa->GetNumberOfTuples() < need) {
        err = karst_set_error(ctx, KARST_EPARSE,
                              "%s: %s array '%s' has %" PRId64 " tuples for %" PRId64 " %ss", path,
                              what, name.c_str(), (karst_int_t)aa->GetNumberOfTuples(), need, what);
        goto cleanup;
      }
      if (auto *sa = vtkStringArray::SafeDownCast(aa)) {
        if (dom == 0 && name == "label") {
          for (karst_int_t v = 0; v < np; v++) {
            const std::string &s = sa->GetValue(v);
            if (!s.empty() && (err = karst_network_set_label(&n, v, s.c_str()))) goto nomem;
          }
        } else {
          karst_log(ctx, KARST_LOG_INFO, "%s: string %s array '%s' ignored", path, what,
                    name.c_str());
        }
        continue;
      }
      auto *da = vtkDataArray::SafeDownCast(aa);
      if (!da) continue;
      if (name.size() >= sizeof(((karst_attr_t *)nullptr)->name)) {
        err = karst_set_error(ctx, KARST_EUNSUPPORTED,
                              "%s: %s array name '%s' is longer than %zu characters", path, what,
                              name.c_str(), sizeof(((karst_attr_t *)nullptr)->name) - 1);
        goto cleanup;
      }
      if (karst_network_attr_find(&n, (karst_attr_domain_t)dom, name.c_str())) {
        karst_log(ctx, KARST_LOG_WARNING, "%s: second %s array named '%s' ignored", path, what,
                  name.c_str());
        continue;
      }
      const int nc = da->GetNumberOfComponents();
      double *d;
      if ((err = karst_network_attr_add(&n, (karst_attr_domain_t)dom, name.c_str(), nc,
                                        is_integral(da), &d)))
        goto nomem;
      for (karst_int_t item = 0; item < count; item++) {
        const karst_int_t tuple = dom == 0 ? item : edge_cell[item];
        for (int c = 0; c < nc; c++)
          d[item * nc + c] = da->GetComponent(tuple, c);
      }
    }
  }
  {
    vtkFieldData *fd = pd->GetFieldData();
    if ((err = karst_network_set_crs(&n, field_string(fd, "crs")))) goto nomem;
    const char *title = field_string(fd, "title");
    if (title && !(n.title = dup_cstr(title))) goto nomem;
  }
  karst_network_destroy(out);
  *out = n;
  karst_network_init(&n);
  err = KARST_SUCCESS;
  goto cleanup;
nomem:
  err = karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory while building the network", path);
cleanup:
  std::free(edge_cell);
  karst_network_destroy(&n);
  return err;
}

/* ------------------------------------------------------------------------ */
/* ParaView collection (.pvd), plain stdio                                   */
/* ------------------------------------------------------------------------ */

/* Write @p s with the five XML special characters escaped (XML 1.0, §2.4). */
void xml_escaped(FILE *f, const char *s) {
  for (; *s; s++)
    switch (*s) {
    case '&':
      std::fputs("&amp;", f);
      break;
    case '<':
      std::fputs("&lt;", f);
      break;
    case '>':
      std::fputs("&gt;", f);
      break;
    case '"':
      std::fputs("&quot;", f);
      break;
    case '\'':
      std::fputs("&apos;", f);
      break;
    default:
      std::fputc(*s, f);
    }
}

karst_error_t write_pvd(karst_ctx_t *ctx, const char *path, int n, const char *const *files) {
  karst_error_t err;
  if ((err = check_path(ctx, path))) return err;
  if (n < 0) return karst_set_error(ctx, KARST_EINVAL, "%s: negative file count %d", path, n);
  if (n > 0 && !files) return karst_set_error(ctx, KARST_EINVAL, "%s: no file list given", path);
  for (int i = 0; i < n; i++) {
    const char *f = files[i];
    if (!f || !*f)
      return karst_set_error(ctx, KARST_EINVAL, "%s: member %d has no file name", path, i);
    if (f[0] == '/')
      return karst_set_error(ctx, KARST_EINVAL,
                             "%s: member %d: '%s' is absolute; give it relative to the .pvd so "
                             "the collection can be moved",
                             path, i, f);
    for (const unsigned char *c = (const unsigned char *)f; *c; c++)
      if (*c < 0x20) /* not allowed in XML 1.0 even when escaped (§2.2) */
        return karst_set_error(ctx, KARST_EINVAL,
                               "%s: member %d: file name contains control character 0x%02x", path,
                               i, *c);
  }
  karst_atomic_file_t af;
  if ((err = karst_atomic_open(ctx, &af, path, "w"))) return err;
  std::fputs("<?xml version=\"1.0\"?>\n"
             "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
             "  <Collection>\n",
             af.fp);
  for (int i = 0; i < n; i++) {
    std::fprintf(af.fp, "    <DataSet timestep=\"%d\" group=\"\" part=\"0\" file=\"", i);
    xml_escaped(af.fp, files[i]);
    std::fputs("\"/>\n", af.fp);
  }
  std::fputs("  </Collection>\n</VTKFile>\n", af.fp);
  return karst_atomic_commit(ctx, &af);
}

/* Run @p body, turning C++ exceptions into karst errors naming @p path. */
template <class F> karst_error_t guarded(karst_ctx_t *ctx, const char *path, F body) {
  try {
    return body();
  } catch (const std::bad_alloc &) {
    return karst_set_error(ctx, KARST_ENOMEM, "%s: out of memory", path ? path : "(no file)");
  } catch (const std::exception &ex) {
    return karst_set_error(ctx, KARST_EEXTERNAL, "%s: VTK failed: %s", path ? path : "(no file)",
                           ex.what());
  } catch (...) {
    return karst_set_error(ctx, KARST_EEXTERNAL, "%s: VTK failed with an unknown exception",
                           path ? path : "(no file)");
  }
}

} // namespace

/* ------------------------------------------------------------------------ */
/* Public entry points                                                       */
/* ------------------------------------------------------------------------ */

/**
 * Decompress one block of a VTK XML file for the pre-check of vtp_check.c
 * (compressor 1: zlib, 2: LZ4, 3: LZMA), with VTK's own decompressors so that the
 * check decodes exactly what the reader will. @p out_len is the size the
 * block header declares (already bounded by the compressor's ratio).
 * @return 0 when the block decompresses to exactly @p out_len bytes.
 */
static int plug_uncompress(int compressor, const unsigned char *in, size_t in_len,
                                      unsigned char *out, size_t out_len) {
  try {
    vtkSmartPointer<vtkDataCompressor> c;
    if (compressor == 1)
      c = vtkSmartPointer<vtkZLibDataCompressor>::New();
    else if (compressor == 2)
      c = vtkSmartPointer<vtkLZ4DataCompressor>::New();
    else if (compressor == 3)
      c = vtkSmartPointer<vtkLZMADataCompressor>::New();
    else
      return -1;
    vtkNew<ErrorCatcher> catcher;
    catcher->watch(c);
    size_t got = c->Uncompress(in, in_len, out, out_len);
    return got == out_len && catcher->errors == 0 ? 0 : -1;
  } catch (...) {
    return -1;
  }
}

/**
 * Write a network as VTK XML PolyData (.vtp) for ParaView.
 *
 * One 2-point line cell per edge (so cell data maps 1:1 to edges, in edge
 * order); node coordinates as Float64 points (exact round trip); every node
 * attribute as point data and every edge attribute as cell data, Int32 when
 * the attribute is marked integer, Float64 otherwise, with its ncomp
 * components; node labels as the point string array "label" (NULL labels
 * written as ""); crs and title as one-value field-data string arrays; and
 * the field-data string arrays "tunnel_type_names" and "node_kind_names",
 * whose value i names tunnel type / node kind i (Paris et al. 2021, §5.3).
 * When an edge attribute "tunnel_type" exists it is the active cell scalar.
 *
 * @param ctx  context for the error message (may be NULL).
 * @param path output file; written to a temporary name and renamed into place.
 * @param net  the network.
 * @return KARST_SUCCESS; KARST_EINVAL for non-finite coordinates, edges
 *         outside the node range, integer attributes holding non-integers;
 *         KARST_EIO when the file cannot be written (nothing is left behind).
 * Time complexity: O(n_nodes + n_edges) times the number of attribute components.
 * Format: VTK File Formats, XML PolyData (VTK User's Guide, 11th ed., §19.3).
 */
static karst_error_t ref_write_network(karst_ctx_t *ctx, const char *path,
                                                 const karst_network_t *net) {
  return guarded(ctx, path, [&] { return write_network(ctx, path, net); });
}

/**
 * Read a VTK XML PolyData file (.vtp) with line cells into a network.
 *
 * Points become nodes (in file order); each line or polyline cell with k
 * points becomes k - 1 consecutive edges; vertex, polygon and strip cells
 * are ignored (with a warning through the context's logger). Numeric point
 * arrays become node attributes and numeric cell arrays edge attributes
 * (integer VTK types are marked integer); a polyline's cell values are
 * repeated on each of its edges. The point string array "label" restores
 * node labels (empty strings stay unlabelled), the field-data string arrays
 * "crs" and "title" restore those fields; other string arrays are ignored.
 *
 * @param ctx  context for the error message (may be NULL).
 * @param path the .vtp file.
 * @param net  an initialised network; on success its previous content is
 *             released and replaced, on failure it is left untouched.
 * @return KARST_SUCCESS; KARST_EIO when the file cannot be opened;
 *         KARST_EPARSE for a file that is not (valid) VTK XML PolyData,
 *         including truncated files, with VTK's reason in the message;
 *         KARST_EUNSUPPORTED for array names longer than 47 characters.
 * Time complexity: O(points + line points) times the number of array components.
 */
static karst_error_t plug_read_network(karst_ctx_t *ctx, const char *path,
                                                karst_network_t *net) {
  return guarded(ctx, path, [&] { return read_network(ctx, path, net); });
}

/**
 * Write a sample cloud as .vtp: one vertex cell per sample, the Int32 point
 * array "source" (karst_sample_source_t), the field-data string array
 * "source_names" (value i names source i) and the Int64 field value
 * "n_key_points".
 *
 * @param ctx  context for the error message (may be NULL).
 * @param path output file (atomic).
 * @param s    the samples (Paris et al. 2021, §4.1).
 * @return KARST_SUCCESS, KARST_EINVAL (bad coordinates or source tags) or KARST_EIO.
 * Time complexity: O(n).
 */
static karst_error_t ref_write_samples(karst_ctx_t *ctx, const char *path,
                                                 const karst_samples_t *s) {
  return guarded(ctx, path, [&] { return write_samples(ctx, path, s); });
}

/**
 * Write a triangle mesh as .vtp polygons, with the Int32 cell array
 * @c tri_label_name ("label" when NULL) when @c tri_label is set, and the
 * Int32 cell array "feature" when @c tri_feature is set; that
 * array is the active cell scalar. A label array named "tunnel_type" comes
 * with the "tunnel_type_names" lookup table in field data.
 *
 * @param ctx  context for the error message (may be NULL).
 * @param path output file (atomic).
 * @param m    the mesh; triangle indices must lie in [0, n_vertices).
 * @return KARST_SUCCESS, KARST_EINVAL (bad coordinates or indices) or KARST_EIO.
 * Time complexity: O(n_vertices + n_triangles).
 */
static karst_error_t ref_write_mesh(karst_ctx_t *ctx, const char *path,
                                              const karst_mesh_t *m) {
  return guarded(ctx, path, [&] { return write_mesh(ctx, path, m); });
}

/**
 * Write a triangle mesh as .vtp polygons with further integer cell arrays
 * (e.g. block_id and block_type), each with m->n_triangles values, besides
 * m->tri_label when set. Atomic, inline binary (see karst_vtk_write_mesh).
 * @return KARST_SUCCESS, KARST_EINVAL (a nameless or missing array), KARST_EIO.
 * Time complexity: O(vertices + triangles × arrays).
 */
static karst_error_t ref_write_mesh_arrays(karst_ctx_t *ctx, const char *path,
                                                     const karst_mesh_t *m, int n_arrays,
                                                     const char *const *names,
                                                     const int *const *arrays) {
  return guarded(ctx, path, [&] { return write_mesh(ctx, path, m, n_arrays, names, arrays); });
}

/**
 * Write polygons (any number of points each) as VTK XML PolyData (.vtp), inline binary, with
 * integer cell arrays (the first is the active scalars) and field-data string lists, atomically.
 * @return KARST_SUCCESS, KARST_EINVAL (a polygon of fewer than 3 points or referring to a point
 *         that does not exist, non-finite coordinates) or KARST_EIO.
 * Time complexity: O(points + polygon vertices + arrays x polygons).
 */
static karst_error_t ref_write_polydata(karst_ctx_t *ctx, const char *path,
                                                  const karst_polydata_t *m) {
  return guarded(ctx, path, [&] { return write_polydata(ctx, path, m); });
}

/**
 * Write a scalar field sampled on a regular grid as VTK XML ImageData (.vti),
 * Float32 point scalars named @p name (x fastest, then y, then z), inline
 * binary. The values are not copied.
 *
 * @param ctx     context for the error message (may be NULL).
 * @param path    output file (atomic).
 * @param dims    points along x, y, z (each >= 1).
 * @param origin  position of the first point, metres (finite).
 * @param spacing distance between points along x, y, z, metres (> 0).
 * @param values  dims[0] * dims[1] * dims[2] values.
 * @param name    name of the point array (e.g. "sdf").
 * @return KARST_SUCCESS, KARST_EINVAL, KARST_ERANGE (more than 2^40 points) or KARST_EIO.
 * Time complexity: O(dims[0] dims[1] dims[2]).
 */
static karst_error_t plug_write_image(karst_ctx_t *ctx, const char *path,
                                               const int dims[3], const double origin[3],
                                               const double spacing[3], const float *values,
                                               const char *name) {
  return guarded(ctx, path,
                 [&] { return write_image(ctx, path, dims, origin, spacing, values, name); });
}

/**
 * Write a ParaView collection (.pvd) whose member i is @p files[i] at time
 * step i, written with plain stdio (the format is three XML elements), names
 * XML-escaped, atomically.
 *
 * @param ctx   context for the error message (may be NULL).
 * @param path  output file (atomic).
 * @param n     number of members (0 gives an empty collection).
 * @param files member paths relative to the directory of @p path (absolute
 *              paths are refused so that a collection stays movable).
 * @return KARST_SUCCESS, KARST_EINVAL (absolute or empty names, control
 *         characters) or KARST_EIO.
 * Time complexity: O(total length of the names).
 */
static karst_error_t plug_write_pvd(karst_ctx_t *ctx, const char *path, int n,
                                             const char *const *files) {
  return guarded(ctx, path, [&] { return write_pvd(ctx, path, n, files); });
}

/** The plugin's table (io/vtk_api_internal.h): its one exported symbol. */
extern "C" __attribute__((visibility("default"))) const karst_i_vtk_api_t *
karst_i_vtk_plugin_api(void) {
  static const karst_i_vtk_api_t api = {
      KARST_I_VTK_API_VERSION, plug_read_network,  plug_write_image,      plug_write_pvd,
      plug_uncompress,         ref_write_network,  ref_write_samples,     ref_write_mesh,
      ref_write_mesh_arrays,   ref_write_polydata,
  };
  return &api;
}
