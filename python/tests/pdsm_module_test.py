"""The pdsm Python module against the command line (ctest: python_module).

Bakes the bundled courtyard (three lights) small through pdsm.bake, then checks that the module
reads what `pdsm info --json` and `pdsm query` read, with the same numbers, from one thread or
several, and that bad input raises a clear error.
"""

import concurrent.futures
import json
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

import pdsm

SOURCE = os.environ.get("PDSM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
COURTYARD = os.path.join(SOURCE, "examples", "courtyard", "scene.json")
PLATES = os.path.join(SOURCE, "examples", "plates", "scene.json")
SMALL = {"resolution": (64, 48), "samples": 8, "sm_resolution": 128, "threads": 2}


def cli(*args):
    return subprocess.run([pdsm._cli(), *args], check=True, capture_output=True, text=True).stdout


def ground_points(n, seed):
    """Points on and above the courtyard's ground, some outside every map."""
    rng = np.random.default_rng(seed)
    points = np.column_stack([rng.uniform(-12, 12, n), rng.choice([0.0, 0.5, 2.0], n),
                              rng.uniform(-12, 12, n)])
    return points


class PdsmModuleTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.path = os.path.join(cls.tmp.name, "courtyard.exr")
        cls.file = pdsm.bake(COURTYARD, cls.path, **SMALL)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_bake_writes_the_bytes_the_command_line_writes(self):
        by_cli = os.path.join(self.tmp.name, "by_cli.exr")
        cli("bake", COURTYARD, "-o", by_cli, "--resolution", "64x48", "--samples", "8",
            "--sm-resolution", "128", "--no-preview")
        with open(by_cli, "rb") as a, open(self.path, "rb") as b:
            self.assertEqual(a.read(), b.read())
        self.assertFalse(os.path.exists(os.path.join(self.tmp.name, "courtyard.png")),
                         "no picture unless preview= is given")

    def test_lights_and_headers_are_what_pdsm_info_says(self):
        self.assertEqual(self.file.lights, ["sun", "lamp", "spot"])
        info = json.loads(cli("info", self.path, "--json"))["lights"]
        self.assertEqual(len(self.file.headers), 3)
        for mine, theirs in zip(self.file.headers, info):
            for key in ("vertices", "maxVerticesPerPixel", "emptyPixels", "refinedPixels"):
                theirs.pop(key)
            self.assertEqual(mine, theirs)
        self.assertEqual(self.file.header, {"lights": self.file.headers})
        self.assertEqual(self.file.headers[0]["resolution"], [64, 48])
        self.assertEqual([h["light"] for h in self.file.headers], ["sun", "rect", "spot"])
        self.assertEqual([h["samples"] for h in self.file.headers], [8, 8, 8],
                         "samples=8 overrides every light's, the spot's own 32 too")

    def test_attenuation_prints_as_pdsm_query_prints(self):
        points = ground_points(2000, seed=1)
        csv = os.path.join(self.tmp.name, "points.csv")
        np.savetxt(csv, points, delimiter=",", fmt="%.17g")
        lines = cli("query", self.path, "--points", csv).splitlines()
        values = self.file.attenuation(points)
        self.assertEqual(values.shape, (2000, 3))
        self.assertEqual(values.dtype, np.float64)
        for line, row in zip(lines, values):
            mine = ["nan" if np.isnan(a) else "%.6f" % a for a in row]
            self.assertEqual(line.split(",")[3:], mine)
        self.assertTrue(np.isnan(values).any(), "some points are outside a map")
        lit_or_shadowed = values[~np.isnan(values)]
        self.assertTrue((lit_or_shadowed > 0.99).any() and (lit_or_shadowed < 0.01).any())
        # One light, by name or index: that column alone, shape (n,).
        for light in ("lamp", 1, -2):
            one = self.file.attenuation(points, light=light)
            self.assertEqual(one.shape, (2000,))
            np.testing.assert_array_equal(one, values[:, 1])

    def test_a_one_light_file_answers_a_vector(self):
        path = os.path.join(self.tmp.name, "plates.exr")
        f = pdsm.bake(PLATES, path, resolution=32, samples=4, sm_resolution=64)
        self.assertEqual(f.header["resolution"], [32, 32])
        self.assertEqual(f.attenuation([[0, 0, 0], [0, 0.1, 0]]).shape, (2,))

    def test_a_sphere_light_is_one_light_of_six_parts(self):
        scene = os.path.join(self.tmp.name, "sphere.json")
        with open(scene, "w") as f:
            json.dump({"name": "bulb", "meshes": [
                {"inline": {"positions": [-8, 0, -8, 8, 0, -8, 8, 0, 8, -8, 0, 8],
                            "indices": [0, 1, 2, 0, 2, 3]}, "role": "RECEIVER_ONLY"},
                {"inline": {"positions": [-1, 2, -1, 1, 2, -1, 1, 2, 1, -1, 2, 1],
                            "indices": [0, 1, 2, 0, 2, 3]}, "role": "CASTER_ONLY"}],
                "lights": [{"name": "lamp", "sphere": {"center": [0, 4, 0], "radius": 0.3}}]}, f)
        path = os.path.join(self.tmp.name, "sphere.exr")
        f = pdsm.bake(scene, path, resolution=32, samples=4, sm_resolution=64)
        self.assertEqual(f.lights, ["lamp"])
        self.assertEqual(len(f.headers), 6)
        points = np.array([[0, 0, 0], [6, 0, 0], [0, 3, 0]])
        values = f.attenuation(points)
        self.assertEqual(values.shape, (3,))
        np.testing.assert_array_equal(values, [1.0, 0.0, 0.0])
        np.testing.assert_array_equal(f.attenuation(points, light="lamp"), values)
        self.assertEqual(f.attenuation(points[1:2], light="lamp@+x")[0], 0.0)

    def test_threads_sharing_a_file_get_the_same_answers(self):
        points = ground_points(20000, seed=2)
        expected = self.file.attenuation(points)
        shared = pdsm.open(self.path, cache_mib=1)  # small: tiles are evicted and re-read
        with concurrent.futures.ThreadPoolExecutor(4) as pool:
            parts = np.array_split(points, 16)
            got = np.concatenate(list(pool.map(shared.attenuation, parts)))
        np.testing.assert_array_equal(got, expected)
        self.assertGreater(shared.tiles_read, 0)

    def test_bad_input_raises_naming_what_is_wrong(self):
        with self.assertRaises(FileNotFoundError):
            pdsm.open(os.path.join(self.tmp.name, "missing.exr"))
        not_pdsm = os.path.join(self.tmp.name, "not.exr")
        with open(not_pdsm, "w") as out:
            out.write("not an EXR")
        with self.assertRaises(pdsm.Error):
            pdsm.open(not_pdsm)
        with self.assertRaisesRegex(ValueError, r"shape \(n, 3\).*\(4,\)"):
            self.file.attenuation(np.zeros(4))
        with self.assertRaisesRegex(ValueError, "moon"):
            self.file.attenuation(np.zeros((1, 3)), light="moon")
        with self.assertRaises(IndexError):
            self.file.attenuation(np.zeros((1, 3)), light=3)
        with self.assertRaisesRegex(TypeError, "sample"):
            pdsm.bake(COURTYARD, os.path.join(self.tmp.name, "x.exr"), sample=4)
        failed = os.path.join(self.tmp.name, "failed.exr")
        with self.assertRaisesRegex(pdsm.BakeError, "samples"):
            pdsm.bake(COURTYARD, failed, samples=0)
        self.assertFalse(os.path.exists(failed))

    def test_docs_example_plots_a_shadow_profile(self):
        plot = os.path.join(self.tmp.name, "profile.png")
        env = dict(os.environ, MPLBACKEND="Agg")
        subprocess.run([sys.executable, os.path.join(SOURCE, "python", "examples",
                                                     "shadow_profile.py"), self.path, plot],
                       check=True, env=env, capture_output=True, text=True)
        with open(plot, "rb") as png:
            self.assertEqual(png.read(8), b"\x89PNG\r\n\x1a\n")


if __name__ == "__main__":
    unittest.main()
