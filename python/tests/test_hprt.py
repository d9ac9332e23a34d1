"""The Python module against the command line and the path tracer.

Run by tests/python.rs (after ``pip install ./python``), which sets ``HPRT_BIN`` to the
``hprt`` program of the same checkout; checked by ``mypy --strict``.
"""

import gc
import json
import os
import subprocess
import tempfile
import unittest
from pathlib import Path
from typing import Callable

import numpy as np
import numpy.typing as npt

import hprt

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
INTERIOR = SCENES / "env" / "interior.exr"
TEAPOT = SCENES / "teapot.toml"


def hprt_program(*args: str) -> None:
    """Runs the command line of this checkout."""
    program = os.environ.get("HPRT_BIN", "hprt")
    subprocess.run([program, *args], check=True, capture_output=True)


class Decompose(unittest.TestCase):
    def test_same_numbers_as_the_command_line(self) -> None:
        # The defaults, and settings that change the answer (8 lights instead of 3).
        cases: list[tuple[list[str], hprt.Decomposition]] = [
            (["--rotate", "30"], hprt.decompose(INTERIOR, rotation_deg=30.0)),
            (
                ["--threshold", "0.02", "--order", "4"],
                hprt.decompose(INTERIOR, threshold=0.02, order=4),
            ),
            (["--mode", "thesis"], hprt.decompose(INTERIOR, mode="thesis")),
        ]
        self.assertGreater(len(cases[1][1].lights), len(cases[0][1].lights))
        for args, got in cases:
            with tempfile.TemporaryDirectory() as folder:
                out = Path(folder) / "lights.json"
                hprt_program("decompose", str(INTERIOR), *args, "-o", str(out))
                expected = json.loads(out.read_text())
            np.testing.assert_allclose(got.sh, np.array(expected["sh"]), rtol=1e-5, atol=1e-7)
            self.assertEqual(len(got.lights), len(expected["lights"]))
            for light, want in zip(got.lights, expected["lights"]):
                np.testing.assert_allclose(light.direction, want["direction"], atol=1e-6)
                np.testing.assert_allclose(light.power, want["power"], rtol=1e-5)
            np.testing.assert_allclose(got.total_power, expected["total_power"], rtol=1e-5)

    def test_an_array_decomposes_as_its_file(self) -> None:
        array = hprt.load_map(INTERIOR)
        self.assertEqual(array.dtype, np.float32)
        self.assertEqual(array.shape[2], 3)
        self.assertEqual(array.shape[1], 2 * array.shape[0])
        from_file = hprt.decompose(INTERIOR, order=3)
        from_array = hprt.decompose(array, order=3)
        np.testing.assert_array_equal(from_file.sh, from_array.sh)
        self.assertEqual(from_file.sh.shape, (9, 3))

    def test_consistent_mode_adds_up_to_the_map(self) -> None:
        result = hprt.decompose(INTERIOR)
        # The SH part's DC term holds the power the lights do not: 4π · Y00 · c00 = √(4π) c00.
        sh_power = np.sqrt(4.0 * np.pi) * result.sh[0]
        lights = sum((np.array(l.power) for l in result.lights), np.zeros(3))
        np.testing.assert_allclose(sh_power + lights, result.total_power, rtol=1e-3)

    def test_a_lights_sh_is_its_power_at_its_direction(self) -> None:
        light = hprt.Light((1.0, 2.0, 3.0), (2.0, 1.0, 0.5))
        sh = light.sh(3)
        self.assertEqual(sh.shape, (9, 3))
        # Y00 = 1/√(4π); band 1 = √(3/4π) (x, y, z) (CONVENTIONS.md, "Spherical harmonics").
        np.testing.assert_allclose(sh[0], np.array(light.power) / np.sqrt(4 * np.pi), rtol=1e-6)
        band1 = np.sqrt(3 / (4 * np.pi)) * np.outer(light.direction, light.power)
        np.testing.assert_allclose(sh[1:4], band1, rtol=1e-5)

    def test_bad_arguments_are_refused(self) -> None:
        with self.assertRaises(ValueError):
            hprt.decompose(np.zeros((4, 4, 3), dtype=np.float32))
        with self.assertRaises(ValueError):
            hprt.decompose(INTERIOR, mode="nonsense")  # type: ignore[arg-type]
        bad = np.ones((8, 16, 3), dtype=np.float32)
        bad[2, 3, 1] = np.nan
        with self.assertRaisesRegex(ValueError, "finite"):
            hprt.decompose(bad)
        with self.assertRaisesRegex(hprt.HprtError, "missing.exr"):
            hprt.decompose("missing.exr")


class BakeAndRender(unittest.TestCase):
    scene: hprt.Scene
    bake: hprt.Bake

    @classmethod
    def setUpClass(cls) -> None:
        cls.scene = hprt.load_scene(TEAPOT)
        cls.bake = hprt.bake(cls.scene, samples=64, bounces=1, order=4)

    def test_the_transfer_is_direct_plus_indirect(self) -> None:
        direct, indirect = self.bake.direct, self.bake.indirect
        self.assertEqual(direct.shape, (self.scene.vertex_count, 3, 16))
        np.testing.assert_allclose(self.bake.transfer, direct + indirect, rtol=1e-6, atol=1e-7)
        # Under a uniform map of radiance 1 (SH DC term √(4π)) a vertex reflects at most what a
        # white unshadowed one does, 1: its DC transfer is at most 1/√(4π).
        self.assertTrue(np.all(direct[:, :, 0] >= 0.0))
        self.assertTrue(np.all(direct[:, :, 0] <= 1.0 / np.sqrt(4.0 * np.pi) + 1e-4))

    def test_the_transfer_is_shared_not_copied(self) -> None:
        direct = self.bake.direct
        self.assertTrue(np.shares_memory(direct, self.bake.direct))
        self.assertFalse(direct.flags.writeable)
        with self.assertRaises(ValueError):
            direct[0, 0, 0] = 1.0
        # The array keeps its bake alive.
        orphan = hprt.bake(self.scene, samples=4, bounces=0, order=2).indirect
        gc.collect()
        self.assertEqual(float(np.abs(orphan).sum()), 0.0)  # no bounces: nothing indirect
        self.assertEqual(orphan.shape, (self.scene.vertex_count, 3, 4))

    def test_a_cached_bake_is_read_back_not_baked_again(self) -> None:
        calls: list[tuple[str, int, int]] = []

        def record(stage: str, done: int, total: int) -> None:
            calls.append((stage, done, total))

        with tempfile.TemporaryDirectory() as folder:
            previous = os.environ.get("HPRT_CACHE")
            os.environ["HPRT_CACHE"] = folder
            try:
                first = hprt.bake(self.scene, samples=8, bounces=0, order=2, cache=True, progress=record)
                self.assertGreater(len(calls), 0)
                self.assertEqual(len(list(Path(folder).glob("bakes/teapot-*.bake"))), 1)
                calls.clear()
                second = hprt.bake(self.scene, samples=8, bounces=0, order=2, cache=True, progress=record)
                self.assertEqual(calls, [])
            finally:
                if previous is None:
                    del os.environ["HPRT_CACHE"]
                else:
                    os.environ["HPRT_CACHE"] = previous
        np.testing.assert_array_equal(second.transfer, first.transfer)
        fresh = hprt.bake(self.scene, samples=8, bounces=0, order=2)
        np.testing.assert_array_equal(fresh.transfer, first.transfer)

    def test_the_bits_do_not_depend_on_threads_and_survive_a_file(self) -> None:
        one = hprt.bake(self.scene, samples=16, bounces=1, order=3, threads=1)
        two = hprt.bake(self.scene, samples=16, bounces=1, order=3, threads=2)
        np.testing.assert_array_equal(one.transfer, two.transfer)
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "teapot.bake"
            one.save(path)
            again = hprt.load_bake(self.scene, path)
            np.testing.assert_array_equal(again.transfer, one.transfer)
            other = hprt.load_scene(SCENES / "thin.toml")
            with self.assertRaisesRegex(hprt.HprtError, "teapot.bake"):
                hprt.load_bake(other, path)

    def test_the_hybrid_agrees_with_the_path_tracer(self) -> None:
        renderer = hprt.Renderer(self.scene, self.bake, width=80, height=60)
        hybrid = renderer.render(INTERIOR, mode="hybrid")
        again = renderer.render(INTERIOR, mode="hybrid")
        np.testing.assert_array_equal(hybrid, again)
        self.assertEqual(hybrid.shape, (60, 80, 3))
        prt = renderer.render(INTERIOR, mode="prt")
        truth = hprt.reference(self.scene, INTERIOR, spp=64, bounces=1, width=80, height=60)
        self.assertEqual(truth.shape, (60, 80, 3))

        def error(image: npt.NDArray[np.float32]) -> float:
            return float(np.abs(image - truth).sum() / truth.sum())

        # Relative L1 over the image: 0.047 for the hybrid, 0.053 for the plain projection
        # (whose order-4 SH blurs the lamps' shadows) when written.
        print(f"teapot 80x60, relative L1 to the path tracer: hybrid {error(hybrid):.3f}, prt {error(prt):.3f}")
        self.assertLess(error(hybrid), 0.06)
        self.assertLess(error(hybrid), error(prt))
        turned = renderer.render(INTERIOR, mode="hybrid", rotation_deg=90.0)
        self.assertGreater(float(np.abs(turned - hybrid).mean()), 1e-3 * float(hybrid.mean()))

    def test_a_decomposition_renders_as_its_map(self) -> None:
        renderer = hprt.Renderer(self.scene, self.bake, width=80, height=60)
        from_map = renderer.render(INTERIOR, rotation_deg=40.0)
        lighting = hprt.decompose(INTERIOR, order=self.bake.order, rotation_deg=40.0)
        given = renderer.render(lighting, background=INTERIOR, rotation_deg=40.0)
        np.testing.assert_array_equal(given, from_map)
        with self.assertRaisesRegex(ValueError, "order"):
            renderer.render(hprt.decompose(INTERIOR, order=self.bake.order + 1))
        with self.assertRaisesRegex(ValueError, "prt"):
            renderer.render(lighting, mode="prt")

    def test_lighting_of_your_own_is_linear_in_its_power(self) -> None:
        renderer = hprt.Renderer(self.scene, self.bake, width=80, height=60)
        sun = hprt.Light((0.3, 1.0, 0.2), (2.0, 1.5, 1.0), radius_deg=1.0)
        brighter = hprt.Light((0.3, 1.0, 0.2), (6.0, 4.5, 3.0), radius_deg=1.0)
        self.assertAlmostEqual(float(np.linalg.norm(sun.direction)), 1.0, places=6)
        sky = np.zeros((16, 3), dtype=np.float32)
        sky[0] = 0.2
        one = renderer.render(hprt.Decomposition(sky, [sun]))
        three = renderer.render(hprt.Decomposition(3.0 * sky, [brighter]))
        self.assertGreater(float(one.mean()), 0.0)
        np.testing.assert_allclose(three, 3.0 * one, rtol=2e-3, atol=1e-4)
        with self.assertRaises(ValueError):
            hprt.Decomposition(np.zeros((5, 3), dtype=np.float32))
        with self.assertRaises(ValueError):
            hprt.Light((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))

    def test_a_camera_is_the_same_for_the_renderer_and_the_path_tracer(self) -> None:
        renderer = hprt.Renderer(self.scene, self.bake, width=80, height=60)
        own = self.scene.camera
        np.testing.assert_array_equal(
            renderer.render(INTERIOR, camera=own), renderer.render(INTERIOR)
        )
        # From the other side and higher: a camera passed to one and not the other, or
        # mirrored, would put the teapot elsewhere in one of the two images.
        x, y, z = own.position
        moved = hprt.Camera((-z, y + 1.0, x), own.target, fov_deg=own.fov_deg + 10.0)
        image = renderer.render(INTERIOR, camera=moved)
        truth = hprt.reference(
            self.scene, INTERIOR, spp=64, bounces=1, width=80, height=60, camera=moved
        )
        front = renderer.render(INTERIOR)
        # Measured when written: 0.039 from this side, 1.7 for the scene's own view (the map turned by the scene's rotation).
        same, mismatched = (float(np.abs(a - truth).sum() / truth.sum()) for a in (image, front))
        print(f"moved camera, relative L1: same view {same:.3f}, mismatched {mismatched:.3f}")
        self.assertLess(same, 0.08)
        self.assertGreater(mismatched, 0.3)

    def test_progress_reaches_its_end_and_a_raising_callback_raises(self) -> None:
        calls: list[tuple[str, int, int]] = []

        def record(stage: str, done: int, total: int) -> None:
            calls.append((stage, done, total))

        hprt.bake(self.scene, samples=8, bounces=1, order=2, progress=record)
        self.assertGreater(len(calls), 2)
        stage, done, total = calls[-1]
        self.assertEqual(done, total, calls[-5:])
        # At most one call per percent of each stage (a stage starts at 0 again).
        self.assertLessEqual(len(calls), 101 * sum(1 for c in calls if c[1] == 0))

        def fail(stage: str, done: int, total: int) -> None:
            raise KeyboardInterrupt("stop")

        with self.assertRaises(KeyboardInterrupt):
            hprt.reference(self.scene, INTERIOR, spp=1, width=16, height=12, progress=fail)

    def test_hostile_arguments_are_refused_before_any_work(self) -> None:
        with self.assertRaisesRegex(ValueError, "threads"):
            hprt.bake(self.scene, samples=1, threads=10**6)
        with self.assertRaisesRegex(ValueError, "spp"):
            hprt.reference(self.scene, INTERIOR, spp=0, width=4, height=3)
        with self.assertRaisesRegex(ValueError, "over the limit"):
            hprt.reference(self.scene, INTERIOR, width=100000, height=100000)
        with self.assertRaisesRegex(ValueError, "coincide"):
            hprt.reference(
                self.scene, INTERIOR, width=4, height=3, camera=hprt.Camera((0, 0, 0), (0, 0, 0))
            )
        with self.assertRaisesRegex(hprt.HprtError, "samples"):
            hprt.bake(self.scene, samples=0)
        with self.assertRaisesRegex(hprt.HprtError, "bad magic"):
            hprt.load_bake(self.scene, ROOT / "README.md")
        with self.assertRaisesRegex(ValueError, "order"):
            hprt.Light((0.0, 1.0, 0.0), (1.0, 1.0, 1.0)).sh(1000)

    def test_objects_carry_their_roles_and_materials(self) -> None:
        objects = self.scene.objects
        self.assertEqual(sum(o.vertex_count for o in objects), self.scene.vertex_count)
        self.assertEqual(sum(o.triangle_count for o in objects), self.scene.triangle_count)
        self.assertTrue(all(o.role == "object" for o in objects))
        composite = hprt.load_scene(SCENES / "teapot_composite.toml")
        self.assertIn("proxy", {o.role for o in composite.objects})
        glossy = hprt.load_scene(SCENES / "teapot_glossy.toml")
        shiny = [o for o in glossy.objects if max(o.specular) > 0.0]
        self.assertTrue(shiny and all(o.shininess > 1.0 for o in shiny))
        self.assertTrue(all(o.metallic is None for o in glossy.objects))
        pbr = hprt.load_scene(SCENES / "teapot_pbr.toml")
        teapot = next(o for o in pbr.objects if o.name == "teapot")
        self.assertEqual(teapot.metallic, 1.0)
        self.assertAlmostEqual(teapot.roughness or 0.0, 0.35, places=6)
        table = next(o for o in pbr.objects if o.name == "table top")
        self.assertIsNone(table.metallic)
        self.assertIsNone(table.roughness)
        self.assertIsNone(table.normal_map_scale)
        self.assertIsNone(table.emission)
        mirror = hprt.load_scene(SCENES / "models" / "NormalTangentMirrorTest.glb")
        scales = [o.normal_map_scale for o in mirror.objects]
        self.assertIn(1.0, scales)  # the panel's map
        self.assertIn(None, scales)  # the ground slab it stands on

    def test_a_missing_file_is_a_file_not_found_error(self) -> None:
        with self.assertRaisesRegex(hprt.HprtError, "no_such_scene.toml"):
            hprt.load_scene("no_such_scene.toml")
        calls: list[Callable[[], object]] = [
            lambda: hprt.load_scene("no_such_scene.toml"),
            lambda: hprt.load_map("no_such_map.exr"),
            lambda: hprt.decompose("no_such_map.exr"),
            lambda: hprt.load_bake(self.scene, "no_such.bake"),
            lambda: hprt.capture("no_such_capture.toml"),
            lambda: hprt.capture(["no_such_photo.jpg"], fov_deg=25.0),
            lambda: hprt.reference(self.scene, "no_such_map.exr", spp=1, width=8, height=6),
        ]
        for call in calls:
            with self.assertRaises(hprt.HprtFileNotFoundError) as raised:
                call()
            self.assertIsInstance(raised.exception, FileNotFoundError)
            self.assertIsInstance(raised.exception, hprt.HprtError)
            self.assertIn("no_such", str(raised.exception))



class SameAsTheCommandLine(unittest.TestCase):
    def test_bake_render_and_reference_are_the_command_lines_bit_for_bit(self) -> None:
        scene = hprt.load_scene(TEAPOT)
        environment = scene.environment
        assert environment is not None
        bake = hprt.bake(scene, samples=64, bounces=1, seed=3)
        renderer = hprt.Renderer(scene, bake, width=96, height=48)
        image = renderer.render(environment)
        truth = hprt.reference(scene, environment, spp=4, bounces=1, width=96, height=48)
        with tempfile.TemporaryDirectory() as folder:
            theirs = Path(folder) / "teapot.bake"
            hprt_program("bake", str(TEAPOT), "--samples", "64", "--bounces", "1", "--seed", "3",
                         "-o", str(theirs))
            cli_bake = hprt.load_bake(scene, theirs)
            np.testing.assert_array_equal(bake.direct, cli_bake.direct)
            np.testing.assert_array_equal(bake.indirect, cli_bake.indirect)
            hprt_program("render", str(TEAPOT), "--bake", str(theirs), "--width", "96",
                         "--height", "48", "-o", str(Path(folder) / "r.png"),
                         "--exr", str(Path(folder) / "r.exr"))
            # 96 × 48 has a map's 2:1 shape: load_map reads the pixels as they are.
            np.testing.assert_array_equal(image, hprt.load_map(Path(folder) / "r.exr"))
            hprt_program("reference", str(TEAPOT), "--spp", "4", "--bounces", "1", "--width", "96",
                         "--height", "48", "-o", str(Path(folder) / "t.exr"))
            np.testing.assert_array_equal(truth, hprt.load_map(Path(folder) / "t.exr"))


class Composite(unittest.TestCase):
    def test_the_true_composite_is_the_command_lines(self) -> None:
        scene = hprt.load_scene(SCENES / "teapot_composite.toml")
        environment = scene.environment
        assert environment is not None
        composite = hprt.reference_composite(
            scene, environment, spp=4, bounces=1, width=96, height=48
        )
        with tempfile.TemporaryDirectory() as folder:
            out = Path(folder) / "composite.exr"
            args = ["--width", "96", "--height", "48", "--spp", "4", "--bounces", "1"]
            hprt_program("reference", str(SCENES / "teapot_composite.toml"), "-o", str(out), *args)
            # A 96 × 48 image has a map's 2:1 shape: load_map reads its pixels as they are.
            expected = hprt.load_map(out)
        np.testing.assert_array_equal(composite.image, expected)
        kinds = composite.kinds
        self.assertEqual(set(np.unique(kinds)), {0, 1, 2})
        # The layers redo the composite: objects as rendered, the ratio only on proxies.
        np.testing.assert_array_equal(composite.image[kinds == 0], composite.objects[kinds == 0])
        self.assertTrue(np.all(composite.objects[kinds != 0] == 0.0))
        self.assertTrue(np.all(composite.ratio[kinds != 1] == 1.0))
        self.assertTrue(np.all(composite.changed <= (kinds == 1)))
        self.assertGreater(int(composite.changed.sum()), 0)
        with self.assertRaisesRegex(ValueError, "backplate"):
            hprt.reference_composite(hprt.load_scene(TEAPOT), INTERIOR, spp=1, width=8, height=6)


class GpuComposite(unittest.TestCase):
    def test_the_gpu_composite_is_the_command_lines(self) -> None:
        scene = hprt.load_scene(SCENES / "teapot_composite.toml")
        bake = hprt.bake(scene, samples=64, bounces=1)
        environment = scene.environment
        assert environment is not None
        renderer = hprt.Renderer(scene, bake, width=96, height=48)
        composite = hprt.composite(renderer, environment)
        occlusion = hprt.composite(renderer, environment, form="occlusion")
        with tempfile.TemporaryDirectory() as folder:
            bake_file, out = Path(folder) / "scene.bake", Path(folder) / "composite.exr"
            bake.save(bake_file)
            hprt_program("render", str(SCENES / "teapot_composite.toml"), "--bake", str(bake_file),
                         "--width", "96", "--height", "48", "-o", str(Path(folder) / "c.png"),
                         "--exr", str(out))
            expected = hprt.load_map(out)
        np.testing.assert_array_equal(composite.image, expected)
        kinds = composite.kinds
        self.assertEqual(set(np.unique(kinds)), {0, 1, 2})
        # The objects' shadows darken the proxies; the backplate alone stays as it is.
        self.assertLess(float(composite.ratio[kinds == 1].min()), 0.9)
        self.assertTrue(np.all(composite.ratio[kinds != 1] == 1.0))
        # The occlusion peer has the same objects and another account of their shadow.
        np.testing.assert_array_equal(occlusion.image[kinds == 0], composite.image[kinds == 0])
        self.assertFalse(np.array_equal(occlusion.image[kinds == 1], composite.image[kinds == 1]))
        # The renderer is reused after a composite: a plain render is the scene's whole frame.
        plain = renderer.render(environment)
        np.testing.assert_array_equal(plain[kinds == 0], composite.image[kinds == 0])
        with self.assertRaisesRegex(ValueError, "form"):
            hprt.composite(renderer, environment, form="live")  # type: ignore[arg-type]
        teapot = hprt.load_scene(TEAPOT)
        with self.assertRaisesRegex(ValueError, "backplate"):
            hprt.composite(hprt.Renderer(teapot, hprt.bake(teapot, samples=16, bounces=0),
                                         width=8, height=6), INTERIOR)


def timeless(value: object) -> object:
    """A report's statistics without what differs from run to run (timings, the adapter's
    name) and the bake's path (a file here, a bake in memory there)."""
    if isinstance(value, dict):
        return {k: timeless(v) for k, v in value.items()
                if not (k.endswith("_ms") or "seconds" in k or k in ("adapter", "bake"))}
    if isinstance(value, list):
        return [timeless(v) for v in value]
    return value


class Report(unittest.TestCase):
    def test_the_report_is_the_command_lines(self) -> None:
        scene = hprt.load_scene(TEAPOT)
        bake = hprt.bake(scene, samples=64, bounces=1)
        maps = [SCENES / "env" / "sunrise.exr", INTERIOR]
        size = dict(width=64, height=48, spp=16, frames=1, thresholds=[0.05, 0.2])
        lines: list[str] = []
        with tempfile.TemporaryDirectory() as folder:
            # Each its own cache: neither reads the other's references.
            mine, theirs = Path(folder) / "mine", Path(folder) / "theirs"
            before = os.environ.get("HPRT_CACHE")
            os.environ["HPRT_CACHE"] = str(Path(folder) / "cache-mine")
            try:
                stats = hprt.report(scene, mine, maps=maps, bake=bake, log=lines.append,
                                    **size)  # type: ignore[arg-type]
            finally:
                if before is None:
                    del os.environ["HPRT_CACHE"]
                else:
                    os.environ["HPRT_CACHE"] = before
            bake_file = Path(folder) / "teapot.bake"
            bake.save(bake_file)
            program = os.environ.get("HPRT_BIN", "hprt")
            subprocess.run(
                [program, "report", str(TEAPOT), "--bake", str(bake_file), "--envs",
                 *map(str, maps), "--width", "64", "--height", "48", "--spp", "16",
                 "--frames", "1", "--thresholds", "0.05", "0.2", "-o", str(theirs)],
                check=True, capture_output=True,
                env=dict(os.environ, HPRT_CACHE=str(Path(folder) / "cache-theirs")),
            )
            expected = json.loads((theirs / "stats.json").read_text())
            self.assertEqual(timeless(stats), timeless(expected))
            self.assertEqual(timeless(json.loads((mine / "stats.json").read_text())),
                             timeless(expected))
            for name in ("sunrise/reference.exr", "sunrise/hybrid-consistent.exr",
                         "interior/prt.exr", "interior/error-hybrid-consistent.png"):
                self.assertEqual((mine / name).read_bytes(), (theirs / name).read_bytes(), name)
            self.assertTrue((mine / "report.html").exists())
        methods = {m["method"]: m["mean"] for m in stats["maps"][0]["methods"]}
        self.assertLess(methods["hybrid/consistent"], methods["prt"])
        self.assertTrue(any(line.startswith("adapter: ") for line in lines), lines)

    def test_a_report_never_replaces_what_it_reads(self) -> None:
        scene = hprt.load_scene(TEAPOT)
        bake = hprt.bake(scene, samples=16, bounces=0)
        with self.assertRaisesRegex(ValueError, "holds"):
            hprt.report(scene, SCENES, maps=[INTERIOR], bake=bake, spp=1, width=8, height=6)
        with tempfile.TemporaryDirectory() as folder:
            for bad in (dict(thresholds=[1.5]), dict(frames=0), dict(spp=0),
                        dict(maps=[INTERIOR], sequence=INTERIOR), dict(path=True)):
                with self.subTest(bad=bad), self.assertRaises(ValueError):
                    hprt.report(scene, Path(folder) / "out", bake=bake, **bad)
            self.assertFalse((Path(folder) / "out").exists())
            with self.assertRaises(FileNotFoundError):
                hprt.report(scene, Path(folder) / "out", maps=[Path(folder) / "missing.exr"],
                            bake=bake, spp=1, width=8, height=6, frames=1)
            self.assertFalse((Path(folder) / "out").exists())


class Capture(unittest.TestCase):
    def test_the_bundled_photographs_give_the_command_lines_map(self) -> None:
        description = SCENES / "capture" / "capture.toml"
        captured = hprt.capture(description, width=128)
        self.assertEqual(captured.map.shape, (64, 128, 3))
        self.assertEqual(captured.response.shape, (256, 3))
        self.assertEqual(captured.warnings, [])
        spread = captured.spread
        assert spread is not None
        self.assertLess(spread, 0.05)
        self.assertGreater(captured.covered, 0.9)
        with tempfile.TemporaryDirectory() as folder:
            out = Path(folder) / "captured.exr"
            hprt_program("capture", str(description), "-o", str(out), "--width", "128")
            expected = hprt.load_map(out)
        np.testing.assert_allclose(captured.map, expected, rtol=1e-6, atol=1e-12)
        # The response it used, given back, gives the same map.
        again = hprt.capture(description, width=128, response=captured.response)
        np.testing.assert_allclose(again.map, captured.map, rtol=1e-5, atol=1e-12)
        with self.assertRaisesRegex(ValueError, "increasing"):
            hprt.capture(description, width=128, response=captured.response[::-1].copy())

    def test_a_list_of_ball_photographs_is_the_description_of_them(self) -> None:
        with tempfile.TemporaryDirectory() as folder:
            # A mirror ball's bracket, photographed by the synthetic camera (its bench's own
            # capture of them may fail: only the photographs are used).
            subprocess.run([os.environ.get("HPRT_BIN", "hprt"), "bench", "capture", str(INTERIOR), "--ball",
                            "--size", "320x240", "--width", "64", "--keep", folder],
                           capture_output=True)
            photos = sorted(Path(folder).glob("ball0_*.jpg"))
            self.assertEqual(len(photos), 4)
            # The synthetic ball: centred, 0.42 of the picture's height across its radius.
            outline = (160.0, 120.0, 0.42 * 240)
            captured = hprt.capture(photos, width=64, fov_deg=25.0, reflectance=(0.6, 0.6, 0.6),
                                    outline=outline)
            description = Path(folder) / "one-view.toml"
            description.write_text("".join(
                f'[[ball]]\nimage = "{p.name}"\nfov = 25.0\nreflectance = [0.6, 0.6, 0.6]\n'
                f"centre = [160.0, 120.0]\nradius = {0.42 * 240}\n\n" for p in photos))
            out = Path(folder) / "captured.exr"
            hprt_program("capture", str(description), "-o", str(out), "--width", "64")
            expected = hprt.load_map(out)
            np.testing.assert_allclose(captured.map, expected, rtol=1e-6, atol=1e-12)
            self.assertGreater(captured.covered, 0.5)
            with self.assertRaisesRegex(ValueError, "fov_deg"):
                hprt.capture(photos)
            with self.assertRaisesRegex(ValueError, "list of photographs"):
                hprt.capture(description, fov_deg=25.0)


if __name__ == "__main__":
    unittest.main()
