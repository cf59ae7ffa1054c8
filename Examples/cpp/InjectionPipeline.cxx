// The design's pipeline, every step a VTK filter joined by SetInputConnection:
//   reader -> threshold (the bone mask) -> injection -> threshold (cement labels) -> isosurface
//   [-> surface distance to the post-injection CT's cement: reader -> registration -> threshold -> isosurface]
// Usage: InjectionPipeline PRE_CT SCENE.json TIP_X TIP_Y TIP_Z OUT.vtp [POST_CT]
//   e.g. InjectionPipeline Data/foam-phantom/pre.nrrd Data/scenes/paper-1ml.json 22.325 21.855 21.75 cement.vtp
//        Data/foam-phantom/post.nrrd
// Writes OUT.vtp, the simulated cement's surface (mm, the CT's frame; with POST_CT, each vertex's distance to
// the experiment's cement surface in DistanceToOtherSurface_mm) and prints the run's headline figures.
#include "cementsph/pipeline/vtkAffineRegistrationFilter.h"
#include "cementsph/pipeline/vtkCementSPHImageReader.h"
#include "cementsph/pipeline/vtkSurfaceDistanceFilter.h"
#include "cementsph/scene/SceneConfig.h"
#include "vtkSPHInjectionFilter.h"

#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkImageThreshold.h>
#include <vtkNew.h>
#include <vtkXMLPolyDataWriter.h>

#include <cstdint>
#include <iostream>
#include <string>

int main(int argc, char** argv) {
  if (argc != 7 && argc != 8) {
    std::cerr << "usage: InjectionPipeline PRE_CT SCENE.json TIP_X TIP_Y TIP_Z OUT.vtp [POST_CT]\n";
    return 2;
  }
  try {
    // The pipeline. The bone mask: the specimen (its fat-filled pores at -100 HU, struts, shell) against the
    // air around it (-1000 HU), far from both at -500 HU whatever the noise; cement outside it is leaked (2).
    vtkNew<vtkCementSPHImageReader> reader;
    reader->SetFileName(argv[1]);
    vtkNew<vtkImageThreshold> bone;
    bone->SetInputConnection(reader->GetOutputPort());
    bone->ThresholdByUpper(-500.0), bone->SetInValue(1), bone->SetOutValue(0), bone->SetOutputScalarTypeToUnsignedChar();
    vtkNew<vtkSPHInjectionFilter> injection;
    injection->SetInputConnection(reader->GetOutputPort());
    injection->SetBoneMaskConnection(bone->GetOutputPort());
    injection->SetScene(cementsph::scene::loadSceneFile(argv[2], {"tip_mm=[" + std::string(argv[3]) + "," + argv[4] + "," + argv[5] + "]"}));
    // VTK 9.1's vtkFlyingEdges3D ignores the direction matrix: right for this axial phantom; for a CT with flipped
    // or swapped axes use vtkLabelIsosurfaceFilter (cementsph/pipeline) in place of these two filters.
    vtkNew<vtkImageThreshold> cement; // labels 1 (cement) and 2 (leaked) as 1: the 0.5-isosurface then lies midway
    cement->SetInputConnection(injection->GetOutputPort(vtkSPHInjectionFilter::LabelMapPort));
    cement->ThresholdByUpper(1), cement->SetInValue(1), cement->SetOutValue(0);
    vtkNew<vtkFlyingEdges3D> surface;
    surface->SetInputConnection(cement->GetOutputPort());
    surface->SetValue(0, 0.5);
    vtkNew<vtkXMLPolyDataWriter> writer;
    writer->SetInputConnection(surface->GetOutputPort());
    writer->SetFileName(argv[6]);

    // The experiment: the post-injection CT registered onto the pre CT, its cement (>= 1500 HU: at least half
    // the phantom's 3000 HU cement), its surface, and the distance between the two surfaces.
    vtkNew<vtkCementSPHImageReader> post;
    vtkNew<vtkAffineRegistrationFilter> registration;
    vtkNew<vtkImageThreshold> postCement;
    vtkNew<vtkFlyingEdges3D> postSurface;
    vtkNew<vtkSurfaceDistanceFilter> distance;
    if (argc == 8) {
      post->SetFileName(argv[7]);
      registration->SetFixedConnection(reader->GetOutputPort());
      registration->SetMovingConnection(post->GetOutputPort());
      postCement->SetInputConnection(registration->GetOutputPort());
      postCement->ThresholdByUpper(1500.0), postCement->SetInValue(1), postCement->SetOutValue(0);
      postSurface->SetInputConnection(postCement->GetOutputPort());
      postSurface->SetValue(0, 0.5);
      distance->SetInputConnection(surface->GetOutputPort());
      distance->SetReferenceConnection(postSurface->GetOutputPort());
      writer->SetInputConnection(distance->GetOutputPort());
    }
    writer->Write();

    // Every filter kept its own error; the first says what went wrong.
    reader->RethrowIfFailed();
    injection->RethrowIfFailed();
    if (argc == 8) post->RethrowIfFailed(), registration->RethrowIfFailed(), distance->RethrowIfFailed();
    const auto* s = injection->GetSummary();
    vtkImageData* labels = injection->GetLabelMapOutput();
    const auto* l = static_cast<const std::uint8_t*>(labels->GetScalarPointer());
    vtkIdType cementVoxels = 0, leaked = 0;
    for (vtkIdType i = 0; i < labels->GetNumberOfPoints(); ++i)
      cementVoxels += l[i] == vtkSPHInjectionFilter::Cement, leaked += l[i] == vtkSPHInjectionFilter::LeakedCement;
    std::cout << "injected " << s->volumeInjectedMl << " ml in " << s->simulatedTimeS << " s (" << s->engine << "), tip pressure "
              << s->finalTipPressurePa << " Pa; label map: " << cementVoxels << " cement voxels, " << leaked
              << " leaked; surface " << argv[6];
    if (argc == 8) std::cout << "; distance to the experiment's cement " << distance->GetErrorMm() << " mm (mean), "
                             << distance->GetHausdorff95Mm() << " mm (95 %)";
    std::cout << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "InjectionPipeline: " << e.what() << "\n";
    return 1;
  }
}
