// The cementsph Python module: volumes as numpy arrays, scenes as dicts, the injection (through
// vtkSPHInjectionFilter, the same code path as `cementsph inject` and a VTK pipeline), registration and DRR.
//
// Conventions (those of the C++ side): a volume is a float32 numpy array indexed [z, y, x] (C order, x
// fastest, as the voxels lie in the file) with a geometry dict {"origin_mm": [x, y, z], "spacing_mm":
// [x, y, z], "direction": 3x3 rows (column j is index axis j's direction)}: the CT's patient frame, LPS, mm.
// Figures keep the units their names say (metrics.json's keys: _ml, _pa, _mm, _s). Errors: ValueError for bad
// input (one line naming the key), RuntimeError for a failed run.
#include "cementsph/drr/ProjectVolume.h"
#include "cementsph/imaging/AffineRegistration.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/SceneConfig.h"
#include "cementsph/surfacemetrics/Isosurface.h"
#include "cementsph/surfacemetrics/SurfaceDistance.h"
#include "cementsph/surfacemetrics/VolumeMetrics.h"
#include "vtkSPHInjectionFilter.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>
#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace py = pybind11;
using Volume = py::array_t<float, py::array::c_style | py::array::forcecast>;

namespace {

// Python object <-> JSON through Python's own json module (exact for numbers, no third converter).
nlohmann::json toJson(const py::handle& object) {
  if (py::isinstance<py::str>(object)) return nlohmann::json::parse(object.cast<std::string>());
  return nlohmann::json::parse(py::module_::import("json").attr("dumps")(object).cast<std::string>());
}
py::object fromJson(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// The geometry dict of a vtkImageData.
py::dict geometryOf(vtkImageData* image) {
  py::dict g;
  const double* o = image->GetOrigin();
  const double* s = image->GetSpacing();
  g["origin_mm"] = std::vector<double>{o[0], o[1], o[2]};
  g["spacing_mm"] = std::vector<double>{s[0], s[1], s[2]};
  std::vector<std::vector<double>> d(3, std::vector<double>(3));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) d[std::size_t(i)][std::size_t(j)] = image->GetDirectionMatrix()->GetElement(i, j);
  g["direction"] = d;
  return g;
}

// A numpy volume [z, y, x] and its geometry as vtkImageData (a copy: the run must not see Python's memory
// change under it while the GIL is released).
vtkSmartPointer<vtkImageData> toImage(const Volume& volume, const py::dict& geometry) {
  if (volume.ndim() != 3) throw std::invalid_argument("volume: a 3-D array [z, y, x] is required, got " + std::to_string(volume.ndim()) + "-D");
  auto vector3 = [&](const char* key, double fallback) {
    std::vector<double> v{fallback, fallback, fallback};
    if (geometry.contains(key)) v = geometry[key].cast<std::vector<double>>();
    if (v.size() != 3) throw std::invalid_argument(std::string("geometry: '") + key + "' must have 3 numbers");
    return v;
  };
  const auto origin = vector3("origin_mm", 0.0), spacing = vector3("spacing_mm", 1.0);
  if (!geometry.contains("spacing_mm")) throw std::invalid_argument("geometry: 'spacing_mm' is required (mm per voxel along x, y, z)");
  for (double s : spacing)
    if (!(s > 0)) throw std::invalid_argument("geometry: 'spacing_mm' must be positive");
  double direction[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (geometry.contains("direction")) {
    const auto rows = geometry["direction"].cast<std::vector<std::vector<double>>>();
    if (rows.size() != 3) throw std::invalid_argument("geometry: 'direction' must be 3 rows of 3");
    for (std::size_t i = 0; i < 3; ++i) {
      if (rows[i].size() != 3) throw std::invalid_argument("geometry: 'direction' must be 3 rows of 3");
      for (std::size_t j = 0; j < 3; ++j) direction[3 * i + j] = rows[i][j];
    }
  }
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(int(volume.shape(2)), int(volume.shape(1)), int(volume.shape(0)));
  image->SetOrigin(origin.data());
  image->SetSpacing(spacing.data());
  image->SetDirectionMatrix(direction);
  image->AllocateScalars(VTK_FLOAT, 1);
  std::memcpy(image->GetScalarPointer(), volume.data(), sizeof(float) * std::size_t(volume.size()));
  return image;
}

// A vtkImageData's first scalar component as a numpy array [z, y, x] (a copy, owned by Python).
template <typename T> py::array_t<T> toArray(vtkImageData* image) {
  int dims[3];
  image->GetDimensions(dims);
  py::array_t<T> a({py::ssize_t(dims[2]), py::ssize_t(dims[1]), py::ssize_t(dims[0])});
  vtkDataArray* s = image->GetPointData()->GetScalars();
  if (s->GetNumberOfComponents() == 1 && s->GetDataTypeSize() == int(sizeof(T)))
    std::memcpy(a.mutable_data(), s->GetVoidPointer(0), sizeof(T) * std::size_t(a.size()));
  else
    for (py::ssize_t i = 0; i < a.size(); ++i) a.mutable_data()[i] = T(s->GetComponent(vtkIdType(i), 0));
  return a;
}

cementsph::scene::SceneConfig sceneOf(const py::handle& scene) {
  nlohmann::json j;
  if (py::isinstance<py::str>(scene)) {
    const std::string text = scene.cast<std::string>();
    // A path to a scene file, or JSON text.
    const auto first = text.find_first_not_of(" \t\r\n");
    if (first != std::string::npos && text[first] == '{') {
      j = nlohmann::json::parse(text);
    } else {
      std::ifstream file(text);
      if (!file) throw std::invalid_argument("scene: cannot read the scene file " + text);
      try {
        j = nlohmann::json::parse(file);
      } catch (const nlohmann::json::exception& e) {
        throw std::invalid_argument("scene: " + text + " is not JSON: " + e.what());
      }
    }
  } else {
    j = toJson(scene);
  }
  if (!j.is_object()) throw std::invalid_argument("scene: a JSON object (dict) is required");
  // The preset first, then the keys over it (as a scene file); validated once a tip is known (inject).
  cementsph::scene::SceneConfig s = cementsph::scene::scenePreset(j.value("scene_preset", std::string("paper")));
  cementsph::scene::applySceneJson(s, j);
  return s;
}

// on_progress(fraction) from the run's thread, with the GIL taken for the call: False stops the run (as
// SetAbortExecute); an exception stops it too and is raised again once the run is back.
struct ProgressRelay {
  py::object callback;
  std::exception_ptr error;
  static void call(vtkObject* caller, unsigned long, void* clientData, void* callData) {
    auto* relay = static_cast<ProgressRelay*>(clientData);
    auto* filter = static_cast<vtkSPHInjectionFilter*>(caller);
    if (relay->error) return;
    py::gil_scoped_acquire acquire;
    try {
      const py::object answer = relay->callback(*static_cast<double*>(callData));
      if (!answer.is_none() && !answer.cast<bool>()) filter->SetAbortExecute(1);
    } catch (...) {
      relay->error = std::current_exception();
      filter->SetAbortExecute(1);
    }
  }
};

py::dict injectPy(const Volume& volume, const py::dict& geometry, const py::object& scene, const py::object& tip,
                  const std::string& outDir, bool progress, const py::object& boneMask, const py::object& onProgress) {
  cementsph::scene::SceneConfig s = sceneOf(scene);
  if (!tip.is_none()) {
    const auto t = tip.cast<std::vector<double>>();
    if (t.size() != 3) throw std::invalid_argument("tip_mm: 3 numbers (mm, the CT's frame) are required");
    s.tipMm = Eigen::Vector3d(t[0], t[1], t[2]);
  }
  s.validate();
  auto ct = toImage(volume, geometry);
  auto filter = vtkSmartPointer<vtkSPHInjectionFilter>::New();
  filter->SetInputData(ct);
  if (!boneMask.is_none()) {
    const Volume mask = boneMask.cast<Volume>();
    if (mask.ndim() != 3 || mask.shape(0) != volume.shape(0) || mask.shape(1) != volume.shape(1) ||
        mask.shape(2) != volume.shape(2))
      throw std::invalid_argument("bone_mask: an array of the volume's shape [z, y, x] is required");
    filter->SetBoneMaskData(toImage(mask, geometry));
  }
  filter->SetScene(s);
  filter->SetOutputDirectory(outDir);
  filter->SetPrintProgress(progress);
  ProgressRelay relay;
  if (!onProgress.is_none()) {
    relay.callback = onProgress;
    auto observer = vtkSmartPointer<vtkCallbackCommand>::New();
    observer->SetCallback(&ProgressRelay::call);
    observer->SetClientData(&relay);
    filter->AddObserver(vtkCommand::ProgressEvent, observer);
  }
  {
    // The run touches no Python object: other Python threads go on meanwhile.
    py::gil_scoped_release release;
    filter->Update();
  }
  if (relay.error) std::rethrow_exception(relay.error);
  filter->RethrowIfFailed();
  py::dict r;
  r["metrics"] = fromJson(nlohmann::json::parse(filter->GetMetricsJSON()));
  r["summary"] = fromJson(filter->GetSummary()->toJson());
  r["simulated_ct"] = toArray<float>(filter->GetSimulatedCTOutput());
  r["labels"] = toArray<std::uint8_t>(filter->GetLabelMapOutput());
  r["geometry"] = geometryOf(filter->GetSimulatedCTOutput());
  vtkPolyData* points = filter->GetCementPointsOutput();
  const vtkIdType n = points->GetNumberOfPoints();
  py::array_t<double> xyz({py::ssize_t(n), py::ssize_t(3)});
  for (vtkIdType i = 0; i < n; ++i) points->GetPoint(i, xyz.mutable_data() + 3 * i);
  r["cement_points"] = xyz;
  py::dict arrays;
  for (int a = 0; a < points->GetPointData()->GetNumberOfArrays(); ++a) {
    vtkDataArray* array = points->GetPointData()->GetArray(a);
    if (!array || !array->GetName()) continue;
    const int c = array->GetNumberOfComponents();
    py::array_t<double> values = c == 1 ? py::array_t<double>({py::ssize_t(n)}) : py::array_t<double>({py::ssize_t(n), py::ssize_t(c)});
    for (vtkIdType i = 0; i < n; ++i)
      for (int k = 0; k < c; ++k) values.mutable_data()[i * c + k] = array->GetComponent(i, k);
    arrays[array->GetName()] = values;
  }
  r["cement_arrays"] = arrays;
  return r;
}

} // namespace

PYBIND11_MODULE(cementsph, m) {
  m.doc() = "CementSPH: bone-cement injection simulation on CT volumes (numpy in, numpy and dicts out)";

  m.def(
      "read_volume",
      [](const std::string& path) {
        vtkSmartPointer<vtkImageData> image;
        {
          py::gil_scoped_release release;
          image = cementsph::imaging::toVtk(cementsph::imaging::readVolume(path));
        }
        return py::make_tuple(toArray<float>(image), geometryOf(image));
      },
      py::arg("path"),
      "A volume (NRRD, MetaImage, NIfTI, DICOM directory) -> (float32 array [z, y, x], geometry dict with "
      "origin_mm, spacing_mm, direction)");

  m.def(
      "write_volume",
      [](const std::string& path, const Volume& volume, const py::dict& geometry) {
        auto image = cementsph::imaging::imageFromVtk(toImage(volume, geometry));
        cementsph::imaging::writeVolume(image, path);
      },
      py::arg("path"), py::arg("volume"), py::arg("geometry"), "Writes a float volume [z, y, x] with its geometry");

  m.def(
      "scene_from_json",
      [](const py::object& scene) { return fromJson(cementsph::scene::toJson(sceneOf(scene))); },
      py::arg("scene"),
      "A scene (dict, JSON text or a scene file's path; keys as in docs/scene-figures.md, over its scene_preset) "
      "-> every value resolved, as a dict");

  m.def("inject", &injectPy, py::arg("volume"), py::arg("geometry"), py::arg("scene"), py::arg("tip_mm") = py::none(),
        py::arg("out_dir") = "", py::arg("progress") = false, py::arg("bone_mask") = py::none(),
        py::arg("on_progress") = py::none(),
        "Injects cement into a CT (HU, [z, y, x]) at tip_mm (or the scene's tip_mm), through vtkSPHInjectionFilter "
        "with the GIL released. Returns a dict: metrics (metrics.json as a dict), summary (the typed summary), "
        "simulated_ct and labels (0 none, 1 cement, 2 leaked) on the INPUT grid ([z, y, x], geometry), "
        "cement_points (N x 3, mm) and cement_arrays (their point arrays). out_dir: also write the run's files. "
        "bone_mask: an array of the volume's shape, non-zero = bone; cement where it is 0 is labelled leaked (2). "
        "on_progress(fraction): called as the run advances (0..1); returning False stops it (metrics: stopped_early).");

  m.def(
      "register",
      [](const Volume& fixed, const py::dict& fixedGeometry, const Volume& moving, const py::dict& movingGeometry) {
        const auto f = cementsph::imaging::imageFromVtk(toImage(fixed, fixedGeometry));
        const auto mv = cementsph::imaging::imageFromVtk(toImage(moving, movingGeometry));
        cementsph::imaging::RegistrationResult r;
        cementsph::imaging::ImageType::Pointer resampled;
        {
          py::gil_scoped_release release;
          r = cementsph::imaging::registerAffine(f, mv);
          resampled = cementsph::imaging::resampleOnto(mv, f, r.transform);
        }
        py::array_t<double> matrix({4, 4});
        const auto a = r.transform->GetMatrix();
        const auto t = r.transform->GetOffset();
        for (int i = 0; i < 4; ++i)
          for (int j = 0; j < 4; ++j)
            matrix.mutable_at(i, j) = i == 3 ? (j == 3 ? 1.0 : 0.0) : j == 3 ? t[unsigned(i)] : a(unsigned(i), unsigned(j));
        py::dict out;
        out["registered"] = toArray<float>(cementsph::imaging::toVtk(resampled));
        out["matrix"] = matrix;
        out["final_metric_hu2"] = r.finalMetric;
        out["seconds"] = r.seconds;
        return out;
      },
      py::arg("fixed"), py::arg("fixed_geometry"), py::arg("moving"), py::arg("moving_geometry"),
      "Affine registration of a post CT (moving) onto a pre CT (fixed), the cement masked out of the metric. "
      "Returns registered (moving resampled on the fixed grid), matrix (4x4: fixed point -> moving point, mm), "
      "final_metric_hu2, seconds");

  m.def(
      "compare",
      [](const Volume& a, const Volume& b, const py::dict& geometry, double sigma) {
        if (a.ndim() != 3 || b.ndim() != 3 || a.shape(0) != b.shape(0) || a.shape(1) != b.shape(1) || a.shape(2) != b.shape(2))
          throw std::invalid_argument("compare: two masks of one shape [z, y, x] are required");
        // Non-zero is inside (a label map's 1 and 2 alike), as 0/1 unsigned char masks.
        auto mask = [&](const Volume& v) {
          auto image = toImage(v, geometry);
          auto out = vtkSmartPointer<vtkImageData>::New();
          out->CopyStructure(image);
          out->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
          auto* o = static_cast<std::uint8_t*>(out->GetScalarPointer());
          const float* in = static_cast<const float*>(image->GetScalarPointer());
          for (vtkIdType i = 0; i < image->GetNumberOfPoints(); ++i) o[i] = in[i] != 0.f;
          return out;
        };
        auto ma = mask(a), mb = mask(b);
        py::dict out;
        cementsph::surfacemetrics::Overlap overlap;
        cementsph::surfacemetrics::SurfaceComparison c;
        double va = 0, vb = 0;
        {
          py::gil_scoped_release release;
          overlap = cementsph::surfacemetrics::overlap(ma, mb);
          va = cementsph::surfacemetrics::volumeMl(ma);
          vb = cementsph::surfacemetrics::volumeMl(mb);
          cementsph::surfacemetrics::IsosurfaceOptions options;
          options.smoothingSigmaVoxels = sigma;
          auto sa = cementsph::surfacemetrics::isosurface(ma, options);
          auto sb = cementsph::surfacemetrics::isosurface(mb, options);
          c = cementsph::surfacemetrics::compareSurfaces(sa, sb);
        }
        out["dice"] = overlap.dice;
        out["jaccard"] = overlap.jaccard;
        out["volume_a_ml"] = va;
        out["volume_b_ml"] = vb;
        out["error_mm"] = c.errorMm;
        out["mean_a_to_b_mm"] = c.aToB.meanMm;
        out["mean_b_to_a_mm"] = c.bToA.meanMm;
        out["hausdorff_mm"] = c.hausdorffMm;
        out["hausdorff95_mm"] = c.hausdorff95Mm;
        return out;
      },
      py::arg("a"), py::arg("b"), py::arg("geometry"), py::arg("smoothing_sigma_voxels") = 1.0,
      "The paper's comparison of two masks on one grid (non-zero inside, e.g. the simulated labels and the "
      "experiment's cement): dice, jaccard, volume_a_ml, volume_b_ml, and between their isosurfaces (Gaussian "
      "pre-smoothing in voxels, as `cementsph compare`) error_mm (the larger mean distance: the paper's "
      "error), mean_a_to_b_mm, mean_b_to_a_mm, hausdorff_mm, hausdorff95_mm");

  m.def(
      "drr",
      [](const Volume& volume, const py::dict& geometry, double sadMm, double sidMm, int rows, int cols,
         double heightMm, double widthMm, const py::object& isocenter, double gantryAngleDeg, bool parallel) {
        cementsph::drr::DRRGeometry g;
        g.sadMm = sadMm, g.sidMm = sidMm, g.rows = rows, g.cols = cols, g.heightMm = heightMm, g.widthMm = widthMm;
        g.gantryAngleDeg = gantryAngleDeg, g.parallel = parallel;
        if (!isocenter.is_none()) {
          const auto c = isocenter.cast<std::vector<double>>();
          if (c.size() != 3) throw std::invalid_argument("isocenter_mm: 3 numbers are required");
          g.isocenterMm = {c[0], c[1], c[2]};
        }
        auto image = toImage(volume, geometry);
        vtkSmartPointer<vtkImageData> projection;
        {
          py::gil_scoped_release release;
          projection = cementsph::drr::projectVolume(image, g);
        }
        // [row, column] with row 0 at the detector's bottom (vtkDRRFilter's convention).
        int dims[3];
        projection->GetDimensions(dims);
        py::array_t<float> a({py::ssize_t(dims[1]), py::ssize_t(dims[0])});
        vtkDataArray* s = projection->GetPointData()->GetScalars();
        for (py::ssize_t i = 0; i < a.size(); ++i) a.mutable_data()[i] = float(s->GetComponent(vtkIdType(i), 0));
        return a;
      },
      py::arg("volume"), py::arg("geometry"), py::arg("sad_mm") = 1000.0, py::arg("sid_mm") = 1500.0,
      py::arg("rows") = 512, py::arg("cols") = 512, py::arg("height_mm") = 400.0, py::arg("width_mm") = 400.0,
      py::arg("isocenter_mm") = py::none(), py::arg("gantry_angle_deg") = 0.0, py::arg("parallel") = false,
      "A digitally reconstructed radiograph (plastimatch's conventions and scaling, vtkDRRFilter): float32 "
      "[row, column], row 0 at the detector's bottom");
}
