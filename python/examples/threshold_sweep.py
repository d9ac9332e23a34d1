"""Sweeps the decomposition's threshold over a map: how many lights, and how much power they
carry. ``python examples/threshold_sweep.py scenes/env/interior.exr``"""

import sys

import numpy as np

import hprt


def main(path: str) -> None:
    environment = hprt.load_map(path)
    for threshold in (0.02, 0.05, 0.1, 0.2, 0.4):
        result = hprt.decompose(environment, threshold=threshold)
        share = sum(light.share for light in result.lights)
        power = float(np.asarray(result.total_power).sum())
        print(f"threshold {threshold:4.2f}: {len(result.lights):2d} lights, {100 * share:5.1f}% of {power:.3g}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "scenes/env/interior.exr")
