#!/usr/bin/env bash
# The test command: installs what it needs and runs every test.
#   - Rust: format and lint checks, then `cargo test` for the whole workspace (release
#     profile, so the physics tests run at full speed and the CLI binary is shared);
#   - Python: a local virtual environment from pinned requirements, the rkforge Python
#     package built into it with maturin, then pytest on tests/.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== cargo fmt / clippy"
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --release -- -D warnings

echo "== cargo test"
cargo test --workspace --release
cargo build --release --workspace
cargo build --release -p rkforge-ros --examples

echo "== python environment"
if [ ! -x .venv/bin/python ]; then
  if ! python3 -m venv .venv; then
    apt-get update -qq && apt-get install -y -qq python3-venv
    python3 -m venv .venv
  fi
fi
.venv/bin/python -m pip install -q --disable-pip-version-check -r tests/requirements.txt

echo "== python package (maturin)"
rm -rf target/python-wheel
.venv/bin/maturin build --release --quiet -m python/Cargo.toml -i .venv/bin/python --out target/python-wheel
.venv/bin/python -m pip install -q --disable-pip-version-check --force-reinstall --no-deps target/python-wheel/rkforge-*.whl

echo "== pytest"
export RKFORGE_BIN="$PWD/target/release/rkforge"
export RKFORGE_ROS_BIN="$PWD/target/release/rkforge-ros"
.venv/bin/python -m pytest -q tests
