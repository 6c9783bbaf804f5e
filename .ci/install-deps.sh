#!/usr/bin/env bash
# Installs the system packages `cargo xtask ci` needs besides Rust:
#   - a C++ compiler: building the fuzz targets compiles libFuzzer
#     (libfuzzer-sys's build script);
#   - for the viewer's real-window test (crates/cli/tests/view_window.rs):
#     Xvfb, xdotool, ImageMagick's `import` (screenshots), and the X client
#     libraries that minifb loads at run time;
#   - for the render-farm test (crates/cli/tests/farm_slurm.rs): a real
#     single-node Slurm (slurmctld, slurmd, sbatch...) and munge.
#   - python3 with venv, for the Mitsuba 3 comparison
#     (crates/cli/tests/mitsuba.rs makes its own venv and pip-installs mitsuba).
# Idempotent: does nothing when everything is there. Where it cannot install
# (no apt-get, not root and no sudo, or apt fails), it says what is missing;
# under CI (`CI` set to anything but empty, `0` or `false`, as .ci/run does)
# it then exits 1, elsewhere 0 (the window tests then skip themselves and
# print why).
set -euo pipefail

in_ci() {
    case "${CI:-}" in
        "" | 0 | false | FALSE | False) return 1 ;;
        *) return 0 ;;
    esac
}

has_lib() {
    # minifb dlopens libX11 and libXcursor.
    command -v ldconfig >/dev/null 2>&1 && ldconfig -p 2>/dev/null | grep -q "$1\.so"
}

# What is missing, as a list of words (empty when nothing is).
missing() {
    local m=()
    command -v c++ >/dev/null 2>&1 || m+=("c++")
    local tool
    for tool in Xvfb xdotool import; do
        command -v "$tool" >/dev/null 2>&1 || m+=("$tool")
    done
    has_lib libX11 || m+=("libX11")
    has_lib libXcursor || m+=("libXcursor")
    for tool in slurmctld slurmd sbatch munged; do
        command -v "$tool" >/dev/null 2>&1 || m+=("$tool")
    done
    python3 -c "import venv, ensurepip" >/dev/null 2>&1 || m+=("python3-venv")
    echo "${m[*]}"
}

give_up() {
    if in_ci; then
        echo "install-deps: error: $1; missing: $(missing). CI needs them (the window and Slurm tests and the fuzz build would fail)" >&2
        exit 1
    fi
    echo "install-deps: warning: $1; missing: $(missing). The window tests will skip themselves and say why" >&2
    exit 0
}

if [ -z "$(missing)" ]; then
    echo "install-deps: c++, Xvfb, xdotool, import, the X libraries, Slurm, munge and python3-venv are present"
    exit 0
fi

if ! command -v apt-get >/dev/null 2>&1; then
    give_up "no apt-get here"
fi
sudo=()
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
        sudo=(sudo -n)
    else
        give_up "not root (and no password-less sudo)"
    fi
fi

export DEBIAN_FRONTEND=noninteractive
packages=(g++ xvfb xdotool imagemagick libx11-6 libxcursor1 slurm-wlm munge python3 python3-venv)
# A mirror can fail for a moment: try a few times before giving up.
for attempt in 1 2 3; do
    if "${sudo[@]}" apt-get update -qq \
        && "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null; then
        break
    fi
    echo "install-deps: attempt $attempt to install ${packages[*]} failed" >&2
    if [ "$attempt" -eq 3 ]; then
        give_up "could not install ${packages[*]}"
    fi
    sleep $((attempt * 10))
done
if [ -n "$(missing)" ]; then
    give_up "installed ${packages[*]}, but something is still missing"
fi
echo "install-deps: installed ${packages[*]}"
