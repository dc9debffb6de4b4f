#!/bin/sh
# canopy-render needs Mesa's EGL + llvmpipe (headless, CPU-only OpenGL); see docs/rendering.md.
# Installs the Debian packages when it can (root or sudo), says exactly what to install when it cannot.
PKGS="libegl1 libegl-mesa0 libgl1-mesa-dri libgl1"
have_libs() {
    ldconfig -p 2>/dev/null | grep -q 'libEGL.so.1' &&
    ldconfig -p 2>/dev/null | grep -q 'libGL.so.1' &&
    { ls /usr/lib/*/dri/swrast_dri.so >/dev/null 2>&1 || ls /usr/lib/*/dri/*_dri.so >/dev/null 2>&1 || ls /usr/lib/dri/*_dri.so >/dev/null 2>&1; } &&
    { ls /usr/share/glvnd/egl_vendor.d/*mesa*.json >/dev/null 2>&1 || ls /etc/glvnd/egl_vendor.d/*mesa*.json >/dev/null 2>&1; }
}
have_libs && exit 0
if command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null && SUDO="sudo -n"
    if [ "$(id -u)" -eq 0 ] || [ -n "$SUDO" ]; then
        echo "installing headless OpenGL (Mesa EGL): $PKGS"
        $SUDO apt-get install -y -q $PKGS >/dev/null 2>&1 ||
            { $SUDO apt-get update -q >/dev/null 2>&1 && $SUDO apt-get install -y -q $PKGS >/dev/null 2>&1; }
        have_libs && exit 0
    fi
fi
echo "canopy-render needs headless OpenGL, which is missing and could not be installed here."
echo "Install it as root:  apt-get install -y $PKGS"
echo "(everything else works without it; the rendering tests are skipped)"
exit 0
