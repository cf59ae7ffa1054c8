#!/usr/bin/env python3
"""The design's pipeline in Python: reader -> threshold (bone mask) -> injection -> isosurface ->
surface distance, with the cementsph module for the CementSPH steps and VTK's own Python (python3-vtk9) for
the rest; numpy arrays carry the volumes between them (the same [z, y, x] order and geometry both ways).

    PYTHONPATH=build/python python3 Examples/python/pipeline.py [--data-dir Data] [--out cement.vtp]

Prints the cement's volumes and its distance to the phantom's registered post-injection cement, and writes
the simulated cement's surface (mm, the CT's frame) with each vertex's distance to the experiment's.
"""
import argparse
import os
import sys

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkFiltersCore import vtkFlyingEdges3D, vtkMassProperties
from vtkmodules.vtkFiltersGeneral import vtkDistancePolyDataFilter
from vtkmodules.vtkImagingCore import vtkImageThreshold
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

import cementsph


def to_vtk(array, geometry):
    """A [z, y, x] array and its geometry as vtkImageData (VTK's x-fastest order is the array's C order)."""
    image = vtkImageData()
    image.SetDimensions(array.shape[2], array.shape[1], array.shape[0])
    image.SetOrigin(geometry["origin_mm"])
    image.SetSpacing(geometry["spacing_mm"])
    image.SetDirectionMatrix(np.ravel(geometry["direction"]).tolist())
    image.GetPointData().SetScalars(numpy_to_vtk(np.ascontiguousarray(array).ravel(), deep=True))
    return image


def from_vtk(image):
    x, y, z = image.GetDimensions()
    return vtk_to_numpy(image.GetPointData().GetScalars()).reshape(z, y, x)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", default=os.path.join(here, "..", "..", "Data"))
    parser.add_argument("--out", default="cement.vtp", help="the simulated cement's surface (.vtp)")
    args = parser.parse_args()
    phantom = os.path.join(args.data_dir, "foam-phantom")

    # The pipeline (VTK 9.1's Python: setters, no keyword constructors).
    ct, geometry = cementsph.read_volume(os.path.join(phantom, "pre.nrrd"))              # reader
    bone = vtkImageThreshold()                                  # the specimen (fat-filled pores, struts, shell)
    bone.SetInputData(to_vtk(ct, geometry))                     # against air: >= -500 HU
    bone.ThresholdByUpper(-500.0), bone.SetInValue(1), bone.SetOutValue(0), bone.Update()
    run = cementsph.inject(ct, geometry, os.path.join(args.data_dir, "scenes", "paper-1ml.json"),
                           tip_mm=[22.325, 21.855, 21.75], bone_mask=from_vtk(bone.GetOutput()))  # injection
    surface = vtkFlyingEdges3D()                                                          # isosurface
    surface.SetInputData(to_vtk((run["labels"] > 0).astype(np.uint8), geometry))  # 1 cement, 2 leaked: both
    surface.SetValue(0, 0.5)
    post, post_geometry = cementsph.read_volume(os.path.join(phantom, "post.nrrd"))       # the experiment,
    registered = cementsph.register(ct, geometry, post, post_geometry)["registered"]      # registered
    post_surface = vtkFlyingEdges3D()
    post_surface.SetInputData(to_vtk((registered - ct >= 1500.0).astype(np.uint8), geometry))
    post_surface.SetValue(0, 0.5)
    distance = vtkDistancePolyDataFilter()                                                # surface distance
    distance.SetInputConnection(0, surface.GetOutputPort())
    distance.SetInputConnection(1, post_surface.GetOutputPort())
    distance.SignedDistanceOff(), distance.ComputeSecondDistanceOff()
    writer = vtkXMLPolyDataWriter()
    writer.SetInputConnection(distance.GetOutputPort())
    writer.SetFileName(args.out)
    writer.Write()

    m = run["metrics"]
    enclosed = vtkMassProperties()
    enclosed.SetInputConnection(surface.GetOutputPort())
    enclosed.Update()
    distances = vtk_to_numpy(distance.GetOutput().GetPointData().GetArray("Distance"))
    print(f"injected {m['volume_injected_ml']:.3f} ml ({m['pressure_model']}); label map "
          f"{np.count_nonzero(run['labels'] == 1) * np.prod(geometry['spacing_mm']) * 1e-3:.3f} ml cement, "
          f"{np.count_nonzero(run['labels'] == 2)} voxels leaked; isosurface encloses {enclosed.GetVolume() * 1e-3:.3f} ml; "
          f"mean distance to the registered post scan's cement {distances.mean():.3f} mm; wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
