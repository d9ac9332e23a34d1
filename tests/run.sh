#!/usr/bin/env bash
# The whole test suite on a fresh Debian machine with Rust: installs the system packages the
# tests need (software Vulkan, a virtual X server, numpy for the bake-format test, Slurm and
# munge, Chromium and its WebDriver for the web viewer), starts a one-node Slurm cluster on
# localhost, installs Mitsuba 3 (pip, into target/mitsuba-venv), builds the Python module and
# the web viewer's module, then runs every test of the workspace.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(mesa-vulkan-drivers libvulkan1 libegl1 libegl-mesa0 libgl1-mesa-dri xvfb xauth python3 python3-numpy python3-venv slurm-wlm munge chromium chromium-driver)
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
    echo "installing ${missing[*]}"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# A one-node Slurm cluster for tests/slurm.rs. If it cannot start, that test fails and says
# why; it never skips.
slurm_log="$PWD/target/slurm-start.log"
mkdir -p target
if ! $sudo tests/slurm/start-cluster.sh >"$slurm_log" 2>&1; then
    echo "Slurm could not be started (see $slurm_log); tests/slurm.rs will fail"
fi

# Mitsuba 3 for the cross-check in tests/mitsuba.rs, in a private virtual environment. If it
# cannot be installed, that test fails and shows this log; it never skips.
venv="$PWD/target/mitsuba-venv"
log="$PWD/target/mitsuba-install.log"
mkdir -p target
if ! "$venv/bin/python" -c "import mitsuba" >/dev/null 2>&1; then
    echo "installing Mitsuba 3 into $venv"
    rm -rf "$venv"
    if ! { python3 -m venv "$venv" &&
        "$venv/bin/pip" install --quiet --disable-pip-version-check "mitsuba==3.9.1"; } >"$log" 2>&1; then
        echo "Mitsuba 3 could not be installed (see $log); tests/mitsuba.rs will fail"
    fi
fi
export HPRT_MITSUBA_PYTHON="$venv/bin/python" HPRT_MITSUBA_INSTALL_LOG="$log"

# The Python module for tests/python.rs: built from this checkout with the documented command
# (`pip install ./python`, maturin) into a private virtual environment, rebuilt every run, with
# what its tests and examples use (numpy, mypy, pytest, matplotlib, tqdm). If it cannot be
# built, that test fails and shows this log; it never skips.
pyvenv="$PWD/target/python-venv"
pylog="$PWD/target/python-install.log"
echo "building the Python module into $pyvenv (log: $pylog)"
if ! {
    { [ -x "$pyvenv/bin/python" ] || python3 -m venv "$pyvenv"; } &&
        "$pyvenv/bin/pip" install --quiet --disable-pip-version-check numpy mypy pytest matplotlib tqdm &&
        "$pyvenv/bin/pip" install --quiet --disable-pip-version-check --force-reinstall --no-deps ./python
} >"$pylog" 2>&1; then
    echo "the Python module could not be built (see $pylog); tests/python.rs will fail"
fi
export HPRT_PYTHON="$pyvenv/bin/python" HPRT_PYTHON_INSTALL_LOG="$pylog"

# The web viewer's WebAssembly module for tests/web.rs (the wasm32 target and wasm-bindgen's
# tool installed when missing). If it cannot be built, that test fails and shows this log.
weblog="$PWD/target/web-build.log"
echo "building the web viewer's module into web/pkg (log: $weblog)"
if ! web/build.sh >"$weblog" 2>&1; then
    echo "the web viewer could not be built (see $weblog); tests/web.rs will fail"
fi
export HPRT_WEB_BUILD_LOG="$weblog"

export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
cargo test --workspace --locked "$@"

# The bake's ray packets are 8-wide vectors: AVX where the building CPU has it (the workspace
# builds for the native CPU), two SSE halves on one without. That portable path is tested too,
# built for the baseline x86-64 in a target folder of its own.
if [ "$(uname -m)" = x86_64 ] && [ $# -eq 0 ]; then
    RUSTFLAGS="-C target-cpu=x86-64" CARGO_TARGET_DIR=target/portable \
        CARGO_PROFILE_DEV_DEBUG=0 cargo test --locked -p foundation --lib bvh::
fi
