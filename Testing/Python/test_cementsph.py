"""The cementsph Python module against oracles that do not come from the code under test.

Run by ctest (Testing/Python/CMakeLists.txt) as `python3 -m unittest -v test_cementsph` with
PYTHONPATH=build/python and CEMENTSPH_DATA_DIR=Data.

  * read_volume: the phantom's shape and spacing as its generation record says (truth.json), exactly; a
    written oblique volume reads back with its geometry (1e-9 mm) and voxels (exact).
  * scene_from_json: the paper preset's values (the paper: 0.05 ml/s, 100 Pa.s, r 0.57 mm, 40 mm region)
    under a dict's keys; an unknown key is one line naming it.
  * inject, a uniform continuum block (150 HU, intact 1000 HU cortex; the oracles of
    Testing/Simulation/ContinuumBoneTest.cxx): the volume injected is flow x time (1e-9); the tip pressure is
    the spherical Darcy pressure mu Q / (4 pi k) (1.2 / a - 1 / R), k by Kozeny-Carman written out here, within
    10 %; the cement ball's radius from the label map (voxels at least half filled) is R = (3 V / (4 pi phi))^(1/3)
    within 3 %; the simulated CT rose by k_HU phi (3000 HU x porosity) in a filled voxel (1e-3 HU) and not at
    all far from the cement (exact); no leak in intact bone; with a bone mask, leaked exactly where it is 0.
  * inject, the foam phantom (pore-resolved, porosity 1 in the pores): the cement points' volumes add up to
    flow x time (1e-9) and the label map holds it within 2 %; the outputs lie on the input grid.
  * the GIL is released during inject: another Python thread never pauses for half the run; on_progress
    sees rising fractions to 1, and returning False stops the run before volume / flow.
  * register: a copy of the phantom moved by a known translation: that translation within 0.05 mm.
  * compare: two concentric voxelised balls: the analytic Dice, the 2 mm between their surfaces, their volumes.
  * drr: a parallel beam through a 20 mm water cube in air: 0.1 x 0.022 /mm x 20 mm (plastimatch's water
    attenuation and its division by 10) on the cube's shadow, 0 beside it (1e-6).
"""
import json
import math
import os
import tempfile
import threading
import time
import unittest

import numpy as np

import cementsph

DATA = os.environ.get("CEMENTSPH_DATA_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "Data"))
PHANTOM = os.path.join(DATA, "foam-phantom")
TIP = [22.325, 21.855, 21.75]
# The uniform block has a cortex all round, so the anatomy takes it for a vertebra and a run needs the
# cannula's direction (a patient CT); these tests use the shaft from straight below they always ran with.
UP = [0.0, 0.0, 1.0]


def truth():
    with open(os.path.join(PHANTOM, "truth.json")) as f:
        return json.load(f)


def uniform_block(n=60, hu=150.0, cortex=1000.0):
    """n^3 voxels of 0.5 mm: uniform trabecular bone inside a 2-voxel cortical shell."""
    v = np.full((n, n, n), hu, np.float32)
    v[:2], v[-2:], v[:, :2], v[:, -2:], v[:, :, :2], v[:, :, -2:] = (cortex,) * 6
    return v, {"origin_mm": [0.0, 0.0, 0.0], "spacing_mm": [0.5, 0.5, 0.5]}


class ReadVolume(unittest.TestCase):
    def test_phantom_shape_and_spacing_as_recorded(self):
        volume, geometry = cementsph.read_volume(os.path.join(PHANTOM, "pre.nrrd"))
        foam = truth()["foam"]
        self.assertEqual(volume.dtype, np.float32)
        self.assertEqual(volume.shape, tuple(reversed(foam["voxels"])))  # [z, y, x]
        np.testing.assert_allclose(geometry["spacing_mm"], foam["spacing_mm"], rtol=1e-12)
        np.testing.assert_allclose(geometry["direction"], np.eye(3), atol=1e-12)

    def test_oblique_volume_round_trip(self):
        c, s = math.cos(0.4), math.sin(0.4)
        geometry = {"origin_mm": [-10.0, 5.5, 200.25], "spacing_mm": [0.6, 0.7, 1.25],
                    "direction": [[1, 0, 0], [0, c, -s], [0, s, c]]}
        volume = np.arange(4 * 5 * 6, dtype=np.float32).reshape(4, 5, 6) - 50
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "oblique.nrrd")
            cementsph.write_volume(path, volume, geometry)
            back, g = cementsph.read_volume(path)
        np.testing.assert_array_equal(back, volume)
        for key in ("origin_mm", "spacing_mm", "direction"):
            np.testing.assert_allclose(g[key], geometry[key], atol=1e-9)

    def test_missing_file_is_one_line(self):
        with self.assertRaises(Exception) as caught:
            cementsph.read_volume(os.path.join(DATA, "no-such-volume.nrrd"))
        self.assertNotIn("\n", str(caught.exception))


class SceneFromJson(unittest.TestCase):
    def test_keys_over_the_paper_preset(self):
        scene = cementsph.scene_from_json({"volume_ml": 0.3, "tip_mm": [1, 2, 3]})
        self.assertEqual(scene["volume_ml"], 0.3)
        self.assertEqual(scene["flow_rate_ml_per_s"], 0.05)
        self.assertEqual(scene["viscosity_pa_s"], 100.0)
        self.assertEqual(scene["particle_radius_mm"], 0.57)
        self.assertEqual(scene["roi_size_mm"], 40.0)
        self.assertEqual(scene["tip_mm"], [1.0, 2.0, 3.0])
        # The same from JSON text and from a scene file.
        self.assertEqual(cementsph.scene_from_json(json.dumps({"volume_ml": 0.3, "tip_mm": [1, 2, 3]})), scene)
        self.assertEqual(cementsph.scene_from_json(os.path.join(DATA, "scenes", "paper-1ml.json"))["volume_ml"], 1.0)

    def test_unknown_key_is_named(self):
        with self.assertRaises(ValueError) as caught:
            cementsph.scene_from_json({"volume_mll": 1})
        self.assertIn("volume_mll", str(caught.exception))
        self.assertNotIn("\n", str(caught.exception))


class InjectUniformBlock(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.volume, cls.geometry = uniform_block()
        cls.result = cementsph.inject(cls.volume, cls.geometry,
                                   {"volume_ml": 1.0, "cannula_wall": False, "snapshot_interval_s": 1000.0, "direction": UP},
                                   tip_mm=[15.0, 15.0, 15.0])
        cls.phi = 1.0 - 150.0 / 1400.0  # marrow 0 HU, bone tissue 1400 HU (BoneCalibration's defaults)

    def test_volume_is_flow_times_time(self):
        m = self.result["metrics"]
        self.assertEqual(m["bone_model"], "continuum")
        self.assertAlmostEqual(m["volume_injected_ml"], 0.05 * m["simulated_time_s"], delta=1e-9)
        self.assertAlmostEqual(m["volume_injected_ml"], 1.0, delta=1e-9)
        self.assertAlmostEqual(self.result["summary"]["volume_injected_ml"], m["volume_injected_ml"], delta=0)

    def test_tip_pressure_is_spherical_darcy(self):
        m = self.result["metrics"]
        phi, d = self.phi, 0.3e-3
        k = d * d * phi ** 3 / (180.0 * (1.0 - phi) ** 2)  # Kozeny-Carman, d = 0.3 mm
        mu, q = 100.0, 0.05e-6
        radius = (3e-6 / (4 * math.pi * phi)) ** (1 / 3)
        a = (3 * m["outlet_source_voxels"] * 0.125e-9 / (4 * math.pi)) ** (1 / 3)
        expected = mu * q / (4 * math.pi * k) * (1.2 / a - 1 / radius)
        self.assertAlmostEqual(m["final_tip_pressure_pa"] / expected, 1.0, delta=0.10)

    def test_label_map_is_the_ball_of_the_porosity(self):
        labels = self.result["labels"]
        self.assertEqual(labels.shape, self.volume.shape)
        self.assertEqual(np.count_nonzero(labels == 2), 0)  # intact cortex: no leak
        radius_mm = (3e-6 / (4 * math.pi * self.phi)) ** (1 / 3) * 1e3
        labelled_mm = (3 * np.count_nonzero(labels == 1) * 0.125 / (4 * math.pi)) ** (1 / 3)
        self.assertAlmostEqual(labelled_mm / radius_mm, 1.0, delta=0.03)

    def test_simulated_ct_rose_by_the_cement(self):
        sim = self.result["simulated_ct"]
        self.assertEqual(sim.shape, self.volume.shape)
        # The tip's voxel (15 mm / 0.5 mm = index 30) is full: 3000 HU x the porosity above its 150 HU.
        self.assertAlmostEqual(float(sim[30, 30, 30] - self.volume[30, 30, 30]), 3000.0 * self.phi, delta=1e-3)
        # Far from the cement (a corner inside the cortex) nothing changed.
        np.testing.assert_array_equal(sim[:8, :8, :8], self.volume[:8, :8, :8])
        self.assertEqual(self.result["geometry"]["spacing_mm"], [0.5, 0.5, 0.5])


    def test_bone_mask_decides_leaked_cement(self):
        # The oracle is the mask itself: cement where it is 0 (z index >= 30, the tip's plane and beyond) is
        # leaked (2), elsewhere cement (1).
        mask = np.ones(self.volume.shape, np.uint8)
        mask[30:] = 0
        run = cementsph.inject(self.volume, self.geometry, {"volume_ml": 1.0, "cannula_wall": False, "direction": UP},
                               tip_mm=[15.0, 15.0, 15.0], bone_mask=mask)
        labels = run["labels"]
        self.assertEqual(np.count_nonzero(labels[30:] == 1), 0)
        self.assertEqual(np.count_nonzero(labels[:30] == 2), 0)
        self.assertGreater(np.count_nonzero(labels[30:] == 2), 100)
        self.assertGreater(np.count_nonzero(labels[:30] == 1), 100)
        with self.assertRaises(ValueError):
            cementsph.inject(self.volume, self.geometry, {"volume_ml": 0.1}, tip_mm=[15.0, 15.0, 15.0],
                             bone_mask=mask[:10])


class InjectPhantom(unittest.TestCase):
    def test_phantom_holds_flow_times_time(self):
        volume, geometry = cementsph.read_volume(os.path.join(PHANTOM, "pre.nrrd"))
        run = cementsph.inject(volume, geometry, os.path.join(DATA, "scenes", "paper-1ml.json"), tip_mm=TIP)
        oracle_mm3 = 0.05 * 20.0 * 1e3
        points = run["cement_points"]
        self.assertEqual(points.shape, (run["metrics"]["cement_points"], 3))
        self.assertAlmostEqual(run["cement_arrays"]["cement_volume_mm3"].sum() / oracle_mm3, 1.0, delta=1e-9)
        labels = run["labels"]
        self.assertEqual(labels.shape, volume.shape)  # the input's grid, not the 40 mm region
        voxel_mm3 = float(np.prod(geometry["spacing_mm"]))
        self.assertAlmostEqual(np.count_nonzero(labels == 1) * voxel_mm3 / oracle_mm3, 1.0, delta=0.02)
        # The cement points lie within 20 mm of the tip (the 40 mm region around it).
        self.assertLess(np.abs(points - np.array(TIP)).max(), 20.0 + 1e-9)

    def test_gil_is_released(self):
        # While inject runs in a worker thread, this thread keeps running Python: the longest pause between two
        # of its steps is far shorter than the run (with the GIL held it would be the whole run; released, it
        # is the interpreter's switch interval, 5 ms, plus the scheduler's share of two busy cores).
        volume, geometry = uniform_block()
        span = {}

        def run():
            span["start"] = time.perf_counter()
            cementsph.inject(volume, geometry, {"volume_ml": 3.0, "cannula_wall": False, "direction": UP}, tip_mm=[15.0, 15.0, 15.0])
            span["end"] = time.perf_counter()

        worker = threading.Thread(target=run)
        worker.start()
        last, longest = time.perf_counter(), 0.0
        while worker.is_alive():
            now = time.perf_counter()
            if "start" in span and now > span["start"]:
                longest = max(longest, now - last)
            last = now
        worker.join()
        duration = span["end"] - span["start"]
        self.assertGreater(duration, 0.05)
        self.assertLess(longest, 0.5 * duration)

    def test_progress_and_stop(self):
        # Progress fractions rise to 1 over a whole run; returning False at the first report stops the run
        # before the end of injection (volume over flow: 1 ml / 0.05 ml/s = 20 s).
        volume, geometry = uniform_block()
        scene = {"volume_ml": 1.0, "cannula_wall": False, "direction": UP}
        seen = []
        cementsph.inject(volume, geometry, scene, tip_mm=[15.0, 15.0, 15.0], on_progress=seen.append)
        self.assertGreater(len(seen), 10)
        self.assertEqual(seen, sorted(seen))
        self.assertEqual(seen[-1], 1.0)
        stopped = cementsph.inject(volume, geometry, scene, tip_mm=[15.0, 15.0, 15.0], on_progress=lambda f: False)
        self.assertTrue(stopped["metrics"]["stopped_early"])
        self.assertLess(stopped["metrics"]["simulated_time_s"], 20.0)

        def broken(fraction):
            raise KeyError("from the callback")

        with self.assertRaises(KeyError):
            cementsph.inject(volume, geometry, scene, tip_mm=[15.0, 15.0, 15.0], on_progress=broken)

    def test_bad_tip_is_one_line(self):
        volume, geometry = uniform_block()
        with self.assertRaises(ValueError) as caught:
            cementsph.inject(volume, geometry, {"volume_ml": 0.1}, tip_mm=[1.0, 2.0])
        self.assertIn("tip_mm", str(caught.exception))
        self.assertNotIn("\n", str(caught.exception))


class Register(unittest.TestCase):
    def test_known_translation(self):
        volume, geometry = cementsph.read_volume(os.path.join(PHANTOM, "pre.nrrd"))
        t = np.array([1.0, -0.5, 0.7])
        moved = dict(geometry, origin_mm=list(np.array(geometry["origin_mm"]) + t))
        r = cementsph.register(volume, geometry, volume, moved)
        np.testing.assert_allclose(r["matrix"][:3, 3], t, atol=0.05)
        np.testing.assert_allclose(r["matrix"][:3, :3], np.eye(3), atol=0.01)
        self.assertEqual(r["registered"].shape, volume.shape)


class Compare(unittest.TestCase):
    def test_concentric_balls(self):
        # Balls of 6 and 8 mm about one centre on 0.5 mm voxels: Dice 2 V6 / (V6 + V8) = 2 * 216 / (216 + 512)
        # (within 0.01: voxelisation), the surfaces 2 mm apart everywhere (within 0.05 mm: the smoothed
        # isosurface's bias is under 0.02 voxel, SurfaceMetricsTest), volumes 4/3 pi r^3 (within 2 %).
        n = 48
        z, y, x = np.meshgrid(*(np.arange(n) * 0.5 - 11.75,) * 3, indexing="ij")
        r = np.sqrt(x * x + y * y + z * z)
        small, large = (r <= 6.0).astype(np.uint8), (r <= 8.0).astype(np.uint8)
        c = cementsph.compare(small, large, {"origin_mm": [0, 0, 0], "spacing_mm": [0.5, 0.5, 0.5]})
        self.assertAlmostEqual(c["dice"], 2 * 216 / (216 + 512), delta=0.01)
        self.assertAlmostEqual(c["error_mm"], 2.0, delta=0.05)
        self.assertAlmostEqual(c["mean_a_to_b_mm"], 2.0, delta=0.05)
        self.assertAlmostEqual(c["volume_a_ml"] / (4 / 3 * math.pi * 6 ** 3 * 1e-3), 1.0, delta=0.02)
        self.assertAlmostEqual(c["volume_b_ml"] / (4 / 3 * math.pi * 8 ** 3 * 1e-3), 1.0, delta=0.02)


class Drr(unittest.TestCase):
    def test_water_cube_line_integral(self):
        volume = np.full((40, 40, 40), -1000.0, np.float32)
        volume[10:30, 10:30, 10:30] = 0.0  # water, 20 mm a side (1 mm voxels)
        geometry = {"origin_mm": [-19.5, -19.5, -19.5], "spacing_mm": [1.0, 1.0, 1.0]}
        image = cementsph.drr(volume, geometry, rows=40, cols=40, height_mm=40.0, width_mm=40.0, parallel=True,
                              isocenter_mm=[0.0, 0.0, 0.0])
        self.assertEqual(image.shape, (40, 40))
        self.assertAlmostEqual(float(image[20, 20]), 0.1 * 0.022 * 20.0, delta=1e-6)
        self.assertAlmostEqual(float(image[2, 2]), 0.0, delta=1e-6)


if __name__ == "__main__":
    unittest.main()
