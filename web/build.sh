#!/usr/bin/env bash
# Builds the page's WebAssembly module into web/pkg (web.js, web_bg.wasm.gz), which `hprt export
# web` copies beside each exported scene. Needs the wasm32 target and wasm-bindgen's command
# line tool at the version of the wasm-bindgen crate in Cargo.lock; installs both when absent
# (the tool into target/web-tools).
set -euo pipefail
cd "$(dirname "$0")/.."
version=$(grep -A1 '^name = "wasm-bindgen"$' Cargo.lock | sed -n 's/^version = "\(.*\)"$/\1/p')
tools="$PWD/target/web-tools"
bindgen="$tools/bin/wasm-bindgen"
rustup target list --installed | grep -qx wasm32-unknown-unknown ||
    rustup target add wasm32-unknown-unknown
if ! [ -x "$bindgen" ] || [ "$("$bindgen" --version)" != "wasm-bindgen $version" ]; then
    echo "installing wasm-bindgen-cli $version into $tools"
    cargo install --quiet wasm-bindgen-cli --version "$version" --root "$tools"
fi
cargo build --locked --release -p web --target wasm32-unknown-unknown
"$bindgen" --target web --no-typescript --out-dir web/pkg \
    target/wasm32-unknown-unknown/release/web.wasm
# Served gzipped and inflated by the page (DecompressionStream): a third of the size, from any
# static file server.
gzip -9 -n -f web/pkg/web_bg.wasm
echo "built web/pkg ($(du -ch web/pkg/* | tail -1 | cut -f1))"
