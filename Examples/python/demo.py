#!/usr/bin/env python3
"""The demo's inject step from Python (what `cementsph demo` does first), without a notebook.

Reads the bundled foam phantom (Data/foam-phantom, made by `cementsph phantom`), injects the phantom's plan
(truth.json: tip, volume, flow rate, viscosity) with the paper's scene, registers the phantom's
post-injection CT onto the pre CT and compares the simulated cement with the post scan's, then prints the
headline figures (`cementsph demo`'s inject and compare figures). The post scan was itself made by this model, so the comparison checks the pipeline, not
the model.

    PYTHONPATH=build/python python3 Examples/python/demo.py [--data-dir Data] [--out DIR]

Needs the cementsph module (build/python, CMake option CEMENTSPH_PYTHON) and numpy.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

import cementsph


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", default=os.path.join(here, "..", "..", "Data"),
                        help="folder holding foam-phantom/ and scenes/")
    parser.add_argument("--out", default="", help="also write the run's files (metrics.json, simulated_ct.nrrd, ...) here")
    args = parser.parse_args()

    phantom = os.path.join(args.data_dir, "foam-phantom")
    with open(os.path.join(phantom, "truth.json")) as f:
        plan = json.load(f)["injection"]
    pre, geometry = cementsph.read_volume(os.path.join(phantom, "pre.nrrd"))

    # The demo's scene: the paper's, with the phantom's plan over it (as `cementsph demo` passes it with --set).
    scene = cementsph.scene_from_json(os.path.join(args.data_dir, "scenes", "paper.json"))
    for key in ("volume_ml", "flow_rate_ml_per_s", "viscosity_pa_s"):
        scene[key] = plan[key]
    print(f"injecting {plan['volume_ml']} ml at {plan['flow_rate_ml_per_s']} ml/s, {plan['viscosity_pa_s']} Pa.s "
          f"at {plan['tip_mm']} mm into the foam phantom ({pre.shape[2]} x {pre.shape[1]} x {pre.shape[0]} voxels)",
          file=sys.stderr)
    run = cementsph.inject(pre, geometry, scene, tip_mm=plan["tip_mm"], out_dir=args.out)
    m = run["metrics"]

    # The experiment: the post scan registered onto the pre scan; its cement is what rose to at least half the
    # phantom's cement HU (3000) above the pre scan, as the simulated label map counts half-filled voxels.
    post, post_geometry = cementsph.read_volume(os.path.join(phantom, "post.nrrd"))
    start = time.perf_counter()
    registered = cementsph.register(pre, geometry, post, post_geometry)
    experiment = (registered["registered"] - pre >= 1500.0).astype(np.uint8)
    comparison = cementsph.compare(run["labels"], experiment, geometry)
    voxel_ml = float(np.prod(geometry["spacing_mm"])) * 1e-3

    print(f"volume injected: {m['volume_injected_ml']:.3f} ml in {m['simulated_time_s']:.1f} s simulated "
          f"({m['wall_time_s']:.2f} s wall, real-time factor {m['real_time_factor']:.1f}); engine {m['pressure_model']}")
    print(f"max tip pressure: {m['max_tip_pressure_pa']:.0f} Pa; syringe (injection) pressure "
          f"{m['max_injection_pressure_pa'] * 1e-6:.3f} MPa; mean spreading distance {m['mean_spreading_distance_mm']:.3f} mm")
    print(f"cement label map: {np.count_nonzero(run['labels'] == 1)} voxels = "
          f"{np.count_nonzero(run['labels'] == 1) * voxel_ml:.3f} ml, {np.count_nonzero(run['labels'] == 2)} leaked; "
          f"simulated CT on the input grid {run['simulated_ct'].shape}")
    print(f"against the registered post scan ({np.count_nonzero(experiment)} voxels of cement there; registration "
          f"and comparison {time.perf_counter() - start:.1f} s): error {comparison['error_mm']:.3f} mm, Hausdorff 95 % "
          f"{comparison['hausdorff95_mm']:.3f} mm, Dice {comparison['dice']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
