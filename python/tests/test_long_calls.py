"""Long calls: Ctrl-C stops them early, and tqdm draws their progress."""

import io
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import hprt

ROOT = Path(__file__).resolve().parents[2]
TEAPOT = ROOT / "scenes" / "teapot.toml"
INTERIOR = ROOT / "scenes" / "env" / "interior.exr"

# Long work on one thread (RAYON_NUM_THREADS=1 below, so as long on any machine): the bake of
# the teapot at 4096 samples (10 s here) and the reference at 4096 samples per pixel (over
# 20 s). The child prints how far its callback saw the work get, if it has one.
CHILD = """
import sys
import hprt

scene = hprt.load_scene(sys.argv[1])
seen = [0.0]

def record(stage: str, done: int, total: int) -> None:
    seen[0] = done / max(total, 1)

progress = record if sys.argv[3] == "callback" else None
small = hprt.bake(scene, samples=16, bounces=0, order=3) if sys.argv[2] == "report" else None
print("started", flush=True)
try:
    if sys.argv[2] == "bake":
        hprt.bake(scene, samples=4096, bounces=1, order=4, progress=progress)
    elif sys.argv[2] == "report":
        # Its lines on stdout: the test interrupts the path tracer, once it has started.
        hprt.report(scene, sys.argv[5], maps=[sys.argv[4]], bake=small, spp=4096, width=320,
                    height=240, frames=1, thresholds=[0.05], progress=progress,
                    log=lambda line: print(line, flush=True))
    else:
        hprt.reference(scene, sys.argv[4], spp=4096, width=320, height=240, progress=progress)
except KeyboardInterrupt:
    print(f"interrupted at {seen[0]:.3f}", flush=True)
    raise
print("finished", flush=True)
"""


@pytest.mark.parametrize("callback", ["none", "callback"])
@pytest.mark.parametrize("call", ["bake", "reference", "report"])
def test_ctrl_c_stops_a_long_call(call: str, callback: str, tmp_path: Path) -> None:
    # Each its own cache: a report must render its reference, not find it.
    env = {**os.environ, "RAYON_NUM_THREADS": "1", "HPRT_CACHE": str(tmp_path / "cache")}
    output = str(tmp_path / "report")
    args = [sys.executable, "-c", CHILD, str(TEAPOT), call, callback, str(INTERIOR), output]
    child = subprocess.Popen(
        args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )
    assert child.stdout is not None
    assert child.stdout.readline().strip() == "started"
    if call == "report":
        # The GPU methods come first and run to their end; the path tracer stops.
        while not child.stdout.readline().startswith("reference:"):
            pass
    time.sleep(1.0)
    interrupted = time.monotonic()
    child.send_signal(signal.SIGINT)
    try:
        out, err = child.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        child.kill()
        child.communicate()
        pytest.fail(f"{call} still running 20 s after Ctrl-C")
    stopped = time.monotonic() - interrupted
    print(f"{call} ({callback}) stopped {stopped:.2f} s after Ctrl-C: {out.strip()}")
    assert "KeyboardInterrupt" in err, err
    assert "finished" not in out
    assert child.returncode != 0
    # A chunk of vertices or an image row, then the next check (every 50 ms).
    assert stopped < 3.0, f"{stopped:.2f} s"
    assert not Path(output).exists(), "an interrupted report writes nothing"
    if callback == "callback":
        fraction = float(out.split("interrupted at ")[1])
        assert fraction < 0.5, out


@pytest.fixture(scope="module")
def scene() -> hprt.Scene:
    return hprt.load_scene(TEAPOT)


def test_tqdm_draws_a_bar_per_stage_and_closes_it(scene: hprt.Scene) -> None:
    buffer = io.StringIO()
    with hprt.TqdmProgress(file=buffer, mininterval=0) as bars:
        hprt.bake(scene, samples=8, bounces=0, order=2, progress=bars)
        hprt.reference(scene, INTERIOR, spp=1, width=16, height=12, progress=bars)
        text = buffer.getvalue()
    for stage, total in (("bake", scene.vertex_count), ("reference", 12)):
        finished = f"{stage}: 100%"
        assert finished in text and f"{total}/{total}" in text, text
    # Each bar closed at its end: one line per bar in the last screen update.
    assert text.count("100%") >= 2, text


def test_tqdm_by_name(scene: hprt.Scene, capsys: pytest.CaptureFixture[str]) -> None:
    for progress in ("tqdm", True):
        hprt.reference(scene, INTERIOR, spp=1, width=16, height=12, progress=progress)
        assert "reference: 100%" in capsys.readouterr().err
    hprt.reference(scene, INTERIOR, spp=1, width=16, height=12, progress=False)
    assert capsys.readouterr().err == ""
    with pytest.raises(ValueError, match="tqdm"):
        hprt.reference(scene, INTERIOR, spp=1, width=4, height=3, progress="bars")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="callable"):
        hprt.bake(scene, samples=1, progress=3)  # type: ignore[arg-type]


def test_tqdm_missing_is_a_clear_error(
    scene: hprt.Scene, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "tqdm", None)
    with pytest.raises(ValueError, match="pip install tqdm"):
        hprt.bake(scene, samples=1, progress="tqdm")
