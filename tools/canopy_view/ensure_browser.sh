#!/bin/sh
# The viewer page's browser test needs a headless Chromium (Debian's chromium-headless-shell, or
# chromium). Installs it when it can (root or sudo), says what to install when it cannot; the test
# is skipped with that message then. Never fails the set-up.
PKGS="chromium-headless-shell"
have_browser() {
    command -v chromium-headless-shell >/dev/null 2>&1 || command -v chromium >/dev/null 2>&1 ||
        command -v chromium-browser >/dev/null 2>&1
}
have_browser && exit 0
if command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null && SUDO="sudo -n"
    if [ "$(id -u)" -eq 0 ] || [ -n "$SUDO" ]; then
        echo "installing a headless browser for the viewer page's test: $PKGS"
        $SUDO apt-get install -y -q $PKGS >/dev/null 2>&1 ||
            { $SUDO apt-get update -q >/dev/null 2>&1 && $SUDO apt-get install -y -q $PKGS >/dev/null 2>&1; }
        have_browser && exit 0
    fi
fi
echo "the viewer page's browser test needs headless Chromium, which is missing and could not be installed here."
echo "Install it as root:  apt-get install -y $PKGS   (the test is skipped without it)"
exit 0
