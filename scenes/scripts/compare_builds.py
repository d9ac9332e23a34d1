"""Runs the same reports, renders and bakes with two builds of hprt and says whether their outputs
are equal: every image, bake and table byte for byte, the statistics files with their timing
fields (and the adapter's name) left out and each build's folder named alike. Each build gets its own empty cache, so neither reads
the other's bakes or references.

    python3 scenes/scripts/compare_builds.py OLD_HPRT NEW_HPRT OUT [--quick]

Exits 0 when every output is equal, 1 otherwise (naming what differs)."""

import csv
import io
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any, Callable, List

SMALL = ["--width", "64", "--height", "48", "--spp", "16", "--frames", "1", "--backend", "vulkan"]


def jobs(out: Path, quick: bool) -> List[List[str]]:
    """The commands run with each build, writing under `out`."""
    runs = [
        ["bake", "scenes/teapot_composite.toml", "--samples", "64", "-o", str(out / "composite.bake")],
        ["report", "scenes/teapot.toml", "--envs", "scenes/env/sunrise.exr", "scenes/env/hall.exr",
         "--thresholds", "0.05", "0.2", *SMALL, "-o", str(out / "per-map")],
        ["report", "scenes/teapot_composite.toml", "--envs", "scenes/env/sunrise.exr", *SMALL,
         "-o", str(out / "composite")],
        ["render", "scenes/teapot_composite.toml", "--bake", str(out / "composite.bake"),
         "--width", "64", "--height", "48", "--backend", "vulkan", "-o", str(out / "composite.exr")],
    ]
    if not quick:
        runs += [
            ["report", "scenes/teapot.toml", "--env-sequence", "scenes/sequences/sun-hall.toml",
             *SMALL, "-o", str(out / "sequence")],
            ["report", "scenes/room.toml", "--path", "--positions", "3", "--probe-spp", "4",
             *SMALL, "-o", str(out / "path")],
        ]
    return runs


def timing(key: str) -> bool:
    return key.endswith("_ms") or "seconds" in key or key == "adapter"


def without_timings(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if not timing(k)}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


def csv_without_timings(text: str) -> List[List[str]]:
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return rows
    keep = [i for i, name in enumerate(rows[0]) if not timing(name)]
    return [[row[i] for i in keep if i < len(row)] for row in rows]


def comparable(path: Path, root: Path) -> Callable[[], Any]:
    """What must be equal in `path`: text files with the build's own folder (`root`, which
    holds its cache) named alike."""
    text = lambda: path.read_text().replace(str(root), "OUT")
    if path.suffix == ".json":
        return lambda: without_timings(json.loads(text()))
    if path.suffix == ".csv":
        return lambda: csv_without_timings(text())
    return path.read_bytes


def run_build(hprt: str, out: Path, quick: bool) -> None:
    env = dict(os.environ, HPRT_CACHE=str(out / "cache"))
    out.mkdir(parents=True, exist_ok=True)
    for args in jobs(out, quick):
        result = subprocess.run([hprt, *args], env=env, capture_output=True, text=True)
        if result.returncode != 0:
            sys.exit(f"{hprt} {' '.join(args)} failed:\n{result.stdout}\n{result.stderr}")


def main() -> None:
    old, new, out = sys.argv[1], sys.argv[2], Path(sys.argv[3])
    quick = "--quick" in sys.argv[4:]
    for tag, hprt in (("old", old), ("new", new)):
        run_build(hprt, out / tag, quick)
    differ, compared, skipped = [], 0, 0
    for path in sorted((out / "old").rglob("*")):
        relative = path.relative_to(out / "old")
        if path.is_dir() or relative.parts[0] == "cache":
            continue
        if path.suffix == ".html":
            skipped += 1  # the same tables as stats.json, with the timings in them
            continue
        other = out / "new" / relative
        compared += 1
        if not other.exists() or comparable(path, out / "old")() != comparable(other, out / "new")():
            differ.append(str(relative))
    extra = [str(p.relative_to(out / "new")) for p in (out / "new").rglob("*")
             if p.is_file() and p.parts[len(out.parts) + 1] != "cache"
             and not (out / "old" / p.relative_to(out / "new")).exists()]
    print(f"compared {compared} files ({skipped} HTML pages skipped)")
    if differ or extra:
        print("differ:", *differ, sep="\n  ")
        print("only in the new build:", *extra, sep="\n  ")
        sys.exit(1)
    print("every output is equal")


if __name__ == "__main__":
    main()
