#!/usr/bin/env bash
# Installs what the viewer's real-window test (crates/view/tests/window.rs)
# needs: Xvfb, xdotool, ImageMagick's `import` (screenshots), and the X
# client libraries that minifb loads at run time. Idempotent: does nothing
# when everything is there. Without root or apt-get it says so and exits 0:
# the test then skips itself with the reason printed.
set -euo pipefail

have_libs() {
    # minifb dlopens libX11 and libXcursor.
    command -v ldconfig >/dev/null 2>&1 || return 1
    local libs
    libs=$(ldconfig -p 2>/dev/null) || return 1
    grep -q 'libX11\.so' <<<"$libs" && grep -q 'libXcursor\.so' <<<"$libs"
}

if command -v Xvfb >/dev/null 2>&1 && command -v xdotool >/dev/null 2>&1 \
    && command -v import >/dev/null 2>&1 && have_libs; then
    echo "install-view-deps: Xvfb, xdotool, import and the X libraries are present"
    exit 0
fi

if ! command -v apt-get >/dev/null 2>&1; then
    echo "install-view-deps: no apt-get here; the window test will skip itself" >&2
    exit 0
fi
if [ "$(id -u)" -ne 0 ]; then
    echo "install-view-deps: not root; the window test will skip itself" >&2
    exit 0
fi

export DEBIAN_FRONTEND=noninteractive
packages=(xvfb xdotool imagemagick libx11-6 libxcursor1)
# A mirror can fail for a moment: try a few times before giving up.
for attempt in 1 2 3; do
    if apt-get update -qq && apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null; then
        echo "install-view-deps: installed ${packages[*]}"
        exit 0
    fi
    echo "install-view-deps: attempt $attempt to install ${packages[*]} failed" >&2
    sleep $((attempt * 10))
done
echo "install-view-deps: WARNING: could not install ${packages[*]}; the window test will skip itself and say why" >&2
exit 0
