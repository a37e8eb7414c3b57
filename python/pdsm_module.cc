// pdsm._pdsm: the C++ half of the `pdsm` Python module (python/pdsm/__init__.py is the other
// half). It reads PDSM files with the same code as `pdsm query`: tiles read on demand through
// a bounded cache (core/pdsm/pdsm_tile_cache.h) and the same bilinear blend, so a point's
// answer here is the double `pdsm query` prints.
//
// Thread safety: a File may be used from several Python threads at once; attenuation()
// releases the GIL while it reads and evaluates, so threads query in parallel.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <glm/glm.hpp>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_header_json.h"
#include "core/pdsm/pdsm_tile_cache.h"
#include "core/util/version.h"

namespace py = pybind11;

namespace pdsm {
namespace {

// pdsm.Error: what a file that cannot be read raises (a missing one: FileNotFoundError).
PyObject* g_error = nullptr;

[[noreturn]] void Raise(const absl::Status& status) {
  PyErr_SetString(absl::IsNotFound(status) ? PyExc_FileNotFoundError : g_error,
                  std::string(status.message()).c_str());
  throw py::error_already_set();
}

class File {
 public:
  File(const std::string& path, int64_t cache_mib) {
    if (cache_mib < 1) throw py::value_error("cache_mib: at least 1");
    absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path);
    if (!reader.ok()) Raise(reader.status());
    cache_ = std::make_unique<PdsmTileCache>(*std::move(reader), cache_mib << 20);
  }

  const std::string& path() const { return cache_->reader().path(); }

  // Light names in file order ("" for the one light of a file whose light has no name); a
  // sphere light once, by its name (its faces are parts: header_json has one per part).
  std::vector<std::string> lights() const {
    std::vector<std::string> names;
    for (const PdsmLightParts& l : LightsOfParts(cache_->reader().headers())) {
      names.push_back(l.name);
    }
    return names;
  }

  // The headers as `pdsm info --json` words them, without its vertex counts (those need the
  // whole file).
  std::vector<std::string> header_json() const {
    std::vector<std::string> out;
    for (const PdsmHeader& h : cache_->reader().headers()) out.push_back(PdsmHeaderJson(h));
    return out;
  }

  // The lights `light` selects: None -> every light; a name; an index into lights().
  std::vector<PdsmLightParts> Lights(
      const std::optional<std::variant<int, std::string>>& light) const {
    const std::vector<PdsmHeader>& headers = cache_->reader().headers();
    std::vector<PdsmLightParts> all = LightsOfParts(headers);
    if (!light) return all;
    const int count = static_cast<int>(all.size());
    if (const int* index = std::get_if<int>(&*light)) {
      if (*index < -count || *index >= count) {
        throw py::index_error(absl::StrCat("light ", *index, ": the file has ", count,
                                           count == 1 ? " light" : " lights"));
      }
      return {all[*index < 0 ? *index + count : *index]};
    }
    absl::StatusOr<PdsmLightParts> found =
        FindLightParts(headers, cache_->reader().path(), std::get<std::string>(*light));
    if (!found.ok()) throw py::value_error(std::string(found.status().message()));
    return {*std::move(found)};
  }

  py::array_t<double> Attenuation(
      const py::array_t<double, py::array::c_style | py::array::forcecast>& points,
      const std::optional<std::variant<int, std::string>>& light) {
    if (points.ndim() != 2 || points.shape(1) != 3) {
      std::string shape = "(";
      for (py::ssize_t d = 0; d < points.ndim(); ++d) {
        absl::StrAppend(&shape, d > 0 ? ", " : "", points.shape(d));
      }
      absl::StrAppend(&shape, points.ndim() == 1 ? ",)" : ")");
      throw py::value_error(
          absl::StrCat("points: an array of shape (n, 3) (world x, y, z), not ", shape));
    }
    const std::vector<PdsmLightParts> lights = Lights(light);
    const size_t n = static_cast<size_t>(points.shape(0));
    std::vector<glm::dvec3> world(n);
    const double* p = points.data();
    for (size_t i = 0; i < n; ++i) world[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    absl::StatusOr<std::vector<double>> values;
    {
      py::gil_scoped_release unlocked;
      values = AttenuationAt(*cache_, lights, world);
    }
    if (!values.ok()) Raise(values.status());
    // One light selected, or a file of one: (n,); every light of several: (n, lights).
    const bool columns = !light && lights.size() > 1;
    py::array_t<double> out = columns ? py::array_t<double>({n, lights.size()})
                                      : py::array_t<double>(static_cast<py::ssize_t>(n));
    std::copy(values->begin(), values->end(), out.mutable_data());
    return out;
  }

  int64_t tiles_read() const { return cache_->tiles_read(); }
  int64_t cache_bytes() const { return cache_->bytes_held(); }

 private:
  std::unique_ptr<PdsmTileCache> cache_;
};

}  // namespace
}  // namespace pdsm

PYBIND11_MODULE(_pdsm, m) {
  using pdsm::File;
  m.doc() = "The C++ half of pdsm: PDSM files read through the code `pdsm query` uses.";
  static py::exception<std::runtime_error> error(m, "Error", PyExc_RuntimeError);
  pdsm::g_error = error.ptr();
  m.attr("__version__") = std::string(pdsm::ProjectVersion());
  m.attr("DEFAULT_CACHE_MIB") = pdsm::kDefaultTileCacheBytes >> 20;
  py::class_<File>(m, "File")
      .def(py::init<const std::string&, int64_t>(), py::arg("path"),
           py::arg("cache_mib") = pdsm::kDefaultTileCacheBytes >> 20)
      .def_property_readonly("path", &File::path)
      .def_property_readonly("light_names", &File::lights)
      .def("header_json", &File::header_json)
      .def("attenuation", &File::Attenuation, py::arg("points"), py::arg("light") = py::none())
      .def_property_readonly("tiles_read", &File::tiles_read)
      .def_property_readonly("cache_bytes", &File::cache_bytes);
}
