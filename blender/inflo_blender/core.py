"""The parts of the inflo Blender add-on that do not need Blender (no ``bpy`` here).

Standard library only, and nothing of inflo: Blender's Python has neither numpy-heavy inflo nor
its venv, so the add-on reads the project's TOML files itself (``tomllib``) and runs the pipeline
in the project's own ``.venv`` through ``make`` in a subprocess. tests/test_blender_addon_core.py
runs this module with inflo's Python (no Blender); the add-on's operators (``__init__.py``) call it.

- :func:`find_species`: every ``pipelines/<species>/species.toml`` of a project, with its title;
- :func:`project_error`: why a folder is not an inflo project (one line), or None;
- :func:`build_steps`: the make commands of a species build, one per stage;
- :class:`Progress`: the build's output lines -> where it stands (stage, tool, frame);
- :func:`error_line`: the one line of a failed build's stderr to show as a report;
- :class:`BuildProcess`: the build in its own process group, read by threads, cancellable;
- :func:`material_color`, :func:`load_colors`, :func:`organ_kind`: the species' colours as
  canopy-render and canopy-export read them (tools/canopy_render/colors.py; the same rules,
  copied: tests compare the two on every species).
"""
from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import threading
import time
import tomllib
import zlib
from dataclasses import dataclass, field
from pathlib import Path

QUALITIES = ("draft", "final")
# stages that make no input of the USD: canopy-render's pictures, the check, and the figures'
# variants (the lily's and yarrow's subdivided keyframes, the dahlia's packed head, the lilac
# without collisions); left out of a Blender build (scope "usd") unless a [usd] part is under
# the stage's folder, run with every stage (scope "all", which is `make <species>`)
NOT_FOR_USD = ("pictures", "check", "smooth", "painted", "packed", "canopy_off")


# --------------------------------------------------------------------------------------- species

@dataclass(frozen=True)
class Species:
    name: str
    title: str
    family: str
    stages: tuple[str, ...]
    folder: Path
    usd_parts: tuple[str, ...] = ()  # the [usd] parts' paths under build/<species>/


def find_species(project) -> tuple[list[Species], list[str]]:
    """The species of a project (sorted by name) and one line per species file that could not be
    read (``pipelines/x/species.toml: line 3: ...``)."""
    found, errors = [], []
    pipelines = Path(project) / "pipelines"
    if not pipelines.is_dir():
        return [], []
    for path in sorted(pipelines.glob("*/species.toml")):
        try:
            with open(path, "rb") as fh:
                data = tomllib.load(fh)
        except (OSError, tomllib.TOMLDecodeError) as exc:
            errors.append(f"{path}: {exc}")
            continue
        name = data.get("name", path.parent.name)
        if not isinstance(name, str) or name != path.parent.name:
            errors.append(f"{path}: expected name = {path.parent.name!r}, found {name!r}")
            continue
        title = data.get("title") if isinstance(data.get("title"), str) else name
        stages = data.get("stages") if isinstance(data.get("stages"), list) else []
        usd = data.get("usd") if isinstance(data.get("usd"), dict) else {}
        parts = usd.get("parts") if isinstance(usd.get("parts"), dict) else {}
        found.append(Species(name, title, str(data.get("family", "")), tuple(str(s) for s in stages),
                             path.parent, tuple(str(v) for v in parts.values())))
    return found, errors


def project_error(project) -> str | None:
    """None for an inflo project folder, else one line saying why it is not one."""
    if not project or not str(project).strip():
        return "no project folder given: pick the inflo repository (the folder with Makefile and pipelines/)"
    p = Path(os.path.expanduser(str(project)))
    if not p.exists():
        return f"{p}: no such folder"
    if not p.is_dir():
        return f"{p}: is a file, expected the inflo project folder"
    if not (p / "Makefile").is_file() or not (p / "pipelines").is_dir():
        return f"{p}: not an inflo project (expected its Makefile and pipelines/ folder)"
    species, errors = find_species(p)
    if not species:
        return f"{p}: no species (pipelines/*/species.toml)" + (f": {errors[0]}" if errors else "")
    return None


def species_by_name(project, name: str) -> Species:
    """The species ``name`` of ``project``; ValueError with one line when there is none."""
    err = project_error(project)
    if err:
        raise ValueError(err)
    species, _ = find_species(Path(os.path.expanduser(str(project))))
    for sp in species:
        if sp.name == name:
            return sp
    raise ValueError(f"no species {name!r} in {project} (found: {', '.join(s.name for s in species)})")


def build_dir(project, species: str) -> Path:
    return Path(os.path.expanduser(str(project))) / "build" / species


# ---------------------------------------------------------------------------------------- build

@dataclass(frozen=True)
class Step:
    label: str           # what the status bar names: "venv", a stage name
    argv: tuple[str, ...]


def build_steps(project, species: Species, quality: str, scope: str = "usd") -> list[Step]:
    """The make commands of a build: the project's venv (``make venv``: made on first use,
    0.1 s when current), then ``make -C pipelines/<species> QUALITY=q <stage>`` for each stage of
    its species.toml in order (scope ``usd``: those the USD needs, :data:`NOT_FOR_USD` left out;
    ``all``: every stage, which is ``make <species>``), ending with ``usd``."""
    if quality not in QUALITIES:
        raise ValueError(f"quality must be draft or final, found {quality!r}")
    if scope not in ("usd", "all"):
        raise ValueError(f"scope must be usd or all, found {scope!r}")
    root = str(Path(os.path.expanduser(str(project))))
    tops = {p.split("/")[0] for p in species.usd_parts}
    stages = [s for s in species.stages if scope == "all" or s not in NOT_FOR_USD or s in tops]
    if "usd" not in stages:
        stages.append("usd")
    steps = [Step("venv", ("make", "-C", root, "--no-print-directory", "venv"))]
    # build/<species>/quality.txt (pipelines/common.mk): what the build's quality is, which the
    # stages the USD needs do not all write; named as make names it, from the real path of the
    # folder make runs in
    real = Path(os.path.realpath(species.folder))
    steps.append(Step("quality", ("make", "-C", str(species.folder), "--no-print-directory", f"QUALITY={quality}",
                                  str(real.parent.parent / "build" / species.name / "quality.txt"))))
    for s in stages:
        steps.append(Step(s, ("make", "-C", str(species.folder), "--no-print-directory", f"QUALITY={quality}", s)))
    return steps


def build_env(project, base=None) -> dict[str, str]:
    """The environment of a build: the project's ``.venv/bin`` first on PATH, and none of the
    Python variables of the process that starts it (Blender's Python is not the build's)."""
    env = dict(os.environ if base is None else base)
    for k in ("PYTHONHOME", "PYTHONPATH", "PYTHONSTARTUP", "VIRTUAL_ENV", "PYTHONEXECUTABLE"):
        env.pop(k, None)
    venv_bin = Path(os.path.expanduser(str(project))) / ".venv" / "bin"
    env["PATH"] = f"{venv_bin}{os.pathsep}{env.get('PATH', '')}"
    return env


_TOOLS = ("floret-animate", "polygonize", "phyllotaxis", "dimorph", "fccompose", "subdivide", "branch-gen",
          "thyrse", "canopy-render", "canopy-export", "canopy-view", "venation", "inflo-sweep", "petal-grow")
_STILL = re.compile(r"^(?P<tool>[\w.-]+): still running, (?P<done>\d+)(?: of (?P<total>\d+))? (?P<unit>[\w ]+?)"
                    r"(?: done)?(?:,| after)")
_OUT = re.compile(r"(?:^|\s)(?:-o|--output)\s+(\S+)")
_FRAME_FILE = re.compile(r"^(?:frame_)?\d{3,}\.(?:obj|floret|rba|png)$")


@dataclass
class Progress:
    """Where a build stands, from its output lines (:meth:`feed`) and its output folder
    (:meth:`poll`: the frame files the running tool has written, so a quiet tool's frames show).

    The status line reads ``lily (draft): 4/7 canopy · fccompose · frame 42``."""
    species: str = ""
    quality: str = ""
    n_steps: int = 1
    step: int = 0
    stage: str = ""
    tool: str = ""
    output: str | None = None
    frames: int | None = None
    of: int | None = None
    unit: str = "frames"
    since: float = 0.0
    cwd: str = ""
    lines: list[str] = field(default_factory=list)

    def start_step(self, index: int, label: str, cwd: str = "") -> None:
        """A step begins; ``cwd``: the folder its make runs in (relative outputs are under it)."""
        self.step, self.stage, self.cwd = index, label, cwd
        self.tool, self.output, self.frames, self.of = "", None, None, None

    def feed(self, line: str) -> bool:
        """Take one line of the build's output; True when it changed what the status shows."""
        line = line.rstrip("\n")
        if not line.strip():
            return False
        self.lines.append(line)
        del self.lines[:-200]
        m = _STILL.match(line.strip())
        if m:
            self.tool = m["tool"]
            self.frames = int(m["done"])
            self.of = int(m["total"]) if m["total"] else None
            self.unit = m["unit"].strip()
            return True
        words = line.strip().split()
        tool = os.path.basename(words[0]) if words else ""
        if tool in _TOOLS or (tool.startswith("python") and len(words) > 1 and words[1].endswith(".py")):
            self.tool = tool if tool in _TOOLS else os.path.basename(words[1])
            out = _OUT.search(line)
            self.output = os.path.join(self.cwd, out.group(1).strip("'\"")) if out else None
            self.frames, self.of, self.unit = None, None, "frames"
            self.since = time.time()
            return True
        return False

    def poll(self) -> bool:
        """Count the frame files the running tool has written to its output folder (those newer
        than its command line: a rerun over an earlier build's frames counts from 0); True when
        it changed."""
        if not self.output or not os.path.isdir(self.output):
            return False
        try:
            n = sum(1 for e in os.scandir(self.output)
                    if _FRAME_FILE.match(e.name) and e.stat().st_mtime >= self.since - 1.0)
        except OSError:
            return False
        if n and n != self.frames and self.of is None:
            self.frames = n
            return True
        return False

    def fraction(self) -> float:
        """0..1: finished steps, plus the running step's share where its frame total is known."""
        inner = 0.0
        if self.frames is not None and self.of:
            inner = min(1.0, self.frames / self.of)
        return min(1.0, (self.step + inner) / max(1, self.n_steps))

    def text(self) -> str:
        head = f"{self.species} ({self.quality})" if self.species else "inflo"
        parts = [f"{head}: {self.step + 1}/{self.n_steps} {self.stage}"]
        if self.tool:
            parts.append(self.tool)
        if self.frames is not None:
            unit = self.unit if self.unit != "frames" else "frame"
            parts.append(f"{unit} {self.frames}" + (f" of {self.of}" if self.of else ""))
        return " · ".join(parts)


_MAKE_NOISE = re.compile(r"^(?:make(?:\[\d+\])?: (?:\*\*\*|Leaving|Entering|Nothing to be done)|Makefile:\d+: \*\*\*)")
_MAKE_STOP = re.compile(r"^(?:[\w./-]*(?:Makefile|\.mk)):\d+: \*\*\* (.*?)\.?\s+Stop\.$")


def error_line(stderr_lines, returncode: int | None = None) -> str:
    """The line of a failed build's stderr a user should read: the last one that is not make's
    own bookkeeping (``make: *** [...] Error 2``); a Makefile's ``$(error ...)`` without its
    ``Makefile:12: *** ... Stop.`` frame; else make's last line; else the exit status."""
    lines = [ln.rstrip() for ln in stderr_lines if ln and ln.strip()]
    for ln in reversed(lines):
        m = _MAKE_STOP.match(ln.strip())
        if m:
            return m.group(1)
        if not _MAKE_NOISE.match(ln.strip()) and not ln.lstrip().startswith(("Traceback", "File \"")):
            return ln.strip()
    if lines:
        return lines[-1].strip()
    return f"the build failed (exit status {returncode})"


class BuildProcess:
    """One build: its steps run one after another, each a make in its own process group (so a
    cancel ends make and the tool it runs, nothing else), stdout and stderr read by two threads
    into one queue of ``(stream, line)``; :meth:`pump` is called from Blender's timer (or a loop
    in background mode) and never blocks."""

    def __init__(self, project, species: Species, quality: str, scope: str = "usd", env=None):
        self.project = Path(os.path.expanduser(str(project)))
        self.species = species
        self.quality = quality
        self.steps = build_steps(self.project, species, quality, scope)
        self.env = build_env(self.project) if env is None else env
        self.progress = Progress(species.name, quality, n_steps=len(self.steps))
        self.stderr: list[str] = []
        self.lines: queue.Queue = queue.Queue()
        self.proc: subprocess.Popen | None = None
        self.index = -1
        self.returncode: int | None = None
        self.cancelled = False
        self.started = time.monotonic()
        self._readers: list[threading.Thread] = []

    # the state: running (None), done (0), failed (non-zero), cancelled
    @property
    def done(self) -> bool:
        return self.returncode is not None

    def _start(self, index: int) -> None:
        self.index = index
        step = self.steps[index]
        self.progress.start_step(index, step.label, step.argv[step.argv.index("-C") + 1])
        self.proc = subprocess.Popen(step.argv, cwd=str(self.project), env=self.env, stdin=subprocess.DEVNULL,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1,
                                     start_new_session=True)
        self._readers = [threading.Thread(target=self._read, args=(name, stream), daemon=True)
                         for name, stream in (("out", self.proc.stdout), ("err", self.proc.stderr))]
        for t in self._readers:
            t.start()

    def _read(self, name: str, stream) -> None:
        try:
            for line in stream:
                self.lines.put((name, line))
        except (OSError, ValueError):
            pass

    def start(self) -> None:
        self._start(0)

    def pump(self) -> tuple[bool, list[tuple[str, str]]]:
        """Read what has come, advance to the next step when one ends; returns (whether the
        status changed, the lines read as (stream, line))."""
        changed, got = False, []
        while True:
            try:
                name, line = self.lines.get_nowait()
            except queue.Empty:
                break
            got.append((name, line))
            if name == "err":
                self.stderr.append(line.rstrip("\n"))
                del self.stderr[:-200]
            changed |= self.progress.feed(line)
        if self.done or self.proc is None:
            return changed, got
        changed |= self.progress.poll()
        rc = self.proc.poll()
        if rc is None:
            return changed, got
        self._close()
        more = self.pump_rest()
        got += more
        if self.cancelled:
            self.returncode = -signal.SIGTERM if rc == 0 else rc
        elif rc != 0:
            self.returncode = rc
        elif self.index + 1 < len(self.steps):
            self._start(self.index + 1)
        else:
            self.returncode = 0
        return True, got

    def _close(self) -> None:
        """The step's process has ended: finish reading its pipes and close them."""
        for t in self._readers:
            t.join(timeout=2)
        for stream in (self.proc.stdout, self.proc.stderr):
            try:
                stream.close()
            except (OSError, ValueError):
                pass

    def pump_rest(self) -> list[tuple[str, str]]:
        got = []
        while True:
            try:
                name, line = self.lines.get_nowait()
            except queue.Empty:
                return got
            got.append((name, line))
            if name == "err":
                self.stderr.append(line.rstrip("\n"))
            self.progress.feed(line)

    def cancel(self, grace: float = 5.0) -> None:
        """End the running step's process group: SIGTERM (make removes the target it was making;
        the tools write atomically, so no half-written output stays), SIGKILL after ``grace``."""
        self.cancelled = True
        proc = self.proc
        if proc is None or proc.poll() is not None:
            if self.returncode is None:
                self.returncode = -signal.SIGTERM
            return
        try:
            os.killpg(proc.pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
        try:
            proc.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            proc.wait()
        self._close()
        self.pump_rest()
        self.returncode = proc.returncode if proc.returncode not in (0, None) else -signal.SIGTERM

    def run(self, on_line=None, interval: float = 0.2) -> int:
        """Run every step to the end (background mode); ``on_line(stream, line)`` for each line."""
        self.start()
        while not self.done:
            _, got = self.pump()
            for name, line in got:
                if on_line:
                    on_line(name, line)
            if not self.done:
                time.sleep(interval)
        return self.returncode

    def error(self) -> str:
        return error_line(self.stderr, self.returncode)


# --------------------------------------------------------------------------------------- colours
# canopy-render's rules (tools/canopy_render/colors.py), copied: Blender's Python has no inflo

NAMED_COLORS = {
    "white": (1.0, 1.0, 1.0), "black": (0.0, 0.0, 0.0), "grey": (0.5, 0.5, 0.5), "gray": (0.5, 0.5, 0.5),
    "cream": (0.96, 0.94, 0.86), "petal-white": (0.96, 0.95, 0.90), "yellow": (0.98, 0.82, 0.20),
    "gold": (0.93, 0.70, 0.15), "orange": (0.96, 0.55, 0.18), "pink": (0.93, 0.55, 0.68),
    "red": (0.78, 0.16, 0.18), "crimson": (0.70, 0.12, 0.22), "lilac": (0.72, 0.60, 0.86),
    "purple": (0.50, 0.28, 0.62), "blue": (0.35, 0.50, 0.85), "brown": (0.45, 0.28, 0.12),
    "green": (0.35, 0.55, 0.22), "leaf": (0.24, 0.45, 0.18), "olive": (0.62, 0.62, 0.28),
}
MATERIAL_PALETTE = (
    (0.96, 0.95, 0.90), (0.98, 0.82, 0.20), (0.93, 0.55, 0.68), (0.45, 0.28, 0.12), (0.35, 0.55, 0.22),
    (0.72, 0.60, 0.86), (0.96, 0.55, 0.18), (0.24, 0.45, 0.18), (0.78, 0.72, 0.35), (0.70, 0.12, 0.22),
)
KEYWORD_COLORS = (
    (("stem", "branch", "stalk", "peduncle", "pedicel", "internode", "axis", "receptacle"), NAMED_COLORS["green"]),
    (("leaf", "sepal", "bract", "involucr"), NAMED_COLORS["leaf"]),
    (("disk", "disc"), NAMED_COLORS["brown"]),
    (("stamen", "anther", "pollen"), (0.80, 0.45, 0.15)),
    (("pistil", "stigma", "style", "carpel"), (0.70, 0.80, 0.45)),
    (("petal", "tepal", "ray", "ligule", "corolla"), MATERIAL_PALETTE[0]),
)
_ID = re.compile(r"^(?:mtl|mat|material)?[ _-]?(\d+)$", re.IGNORECASE)
_HEX = re.compile(r"^#?([0-9a-fA-F]{6})$")


def parse_color(value):
    """``[r, g, b]`` in 0..1, ``"#rrggbb"``, ``"r,g,b"`` or a colour name -> (r, g, b); ValueError."""
    if isinstance(value, str):
        text = value.strip().lower()
        if text in NAMED_COLORS:
            return NAMED_COLORS[text]
        m = _HEX.match(text)
        if m and (text.startswith("#") or not re.fullmatch(r"[0-9.,\s]+", text)):
            h = m.group(1)
            return tuple(int(h[i:i + 2], 16) / 255.0 for i in (0, 2, 4))
        parts = [p for p in re.split(r"[,\s]+", text) if p]
    else:
        try:
            parts = list(value)
        except TypeError:
            parts = []
    try:
        rgb = tuple(float(p) for p in parts)
    except (TypeError, ValueError):
        rgb = ()
    if len(rgb) != 3 or not all(0.0 <= c <= 1.0 for c in rgb):  # NaN fails the bounds too
        raise ValueError(f"expected r,g,b in 0..1, #rrggbb or a colour name, found {value!r}")
    return rgb


def load_colors(path) -> tuple[dict[str, tuple], dict[str, str]]:
    """A species' colors.toml: (material key -> sRGB, material key -> the line's comment, which
    names the organ: ``4 = [0.98, 0.52, 0.14]   # petals``). A missing file is no colours;
    ValueError with the file and the reason for a malformed one."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        return {}, {}
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: {exc}") from None
    colors = {}
    for key, value in data.items():
        try:
            colors[str(key).strip()] = parse_color(value)
        except ValueError as exc:
            raise ValueError(f"{path}: key {key!r}: {exc}") from None
    comments = {}
    for line in raw.decode("utf-8").splitlines():
        m = re.match(r'^\s*("?)([^"=#]+?)\1\s*=.*?#\s*(.+?)\s*$', line)
        if m:
            comments[m.group(2).strip()] = m.group(3)
    return colors, comments


def material_id(name: str) -> int | None:
    m = _ID.match(name.strip())
    return int(m.group(1)) if m else None


def material_color(name: str, table=None):
    """The sRGB colour of material ``name``: canopy-render's rule 3 (colors.py)."""
    table = table or {}
    key = name.strip()
    if key in table:
        return table[key]
    mid = material_id(key)
    if mid is not None:
        for k in (str(mid), f"mtl{mid}"):
            if k in table:
                return table[k]
    low = key.lower()
    if low in table:
        return table[low]
    if mid is None:
        if low in NAMED_COLORS:
            return NAMED_COLORS[low]
        for words, rgb in KEYWORD_COLORS:
            if any(w in low for w in words):
                return rgb
        return MATERIAL_PALETTE[zlib.crc32(key.encode("utf-8")) % len(MATERIAL_PALETTE)]
    return MATERIAL_PALETTE[mid % len(MATERIAL_PALETTE)]


def material_comment(name: str, comments) -> str:
    """The colors.toml comment of material ``name`` (found as :func:`material_color` finds its key)."""
    key = name.strip()
    mid = material_id(key)
    for k in (key, *((str(mid), f"mtl{mid}") if mid is not None else ()), key.lower()):
        if k in comments:
            return comments[k]
    return ""


# organ words -> how the surface is shaded; first match wins, so "receptacle and sepals" is a stem
ORGANS = (
    ("stem", ("stem", "branch", "stalk", "peduncle", "pedicel", "internode", "axis", "receptacle")),
    ("reproductive", ("stamen", "anther", "pollen", "filament", "pistil", "stigma", "style", "carpel",
                      "stylopod")),
    ("leaf", ("leaf", "bract", "involucr", "calyx")),
    ("petal", ("petal", "tepal", "sepal", "ligule", "corolla", "ray", "limb", "lobe", "floret")),
)


def organ_kind(name: str, comment: str = "") -> str:
    """``petal``, ``leaf``, ``stem`` or ``reproductive`` for a material, from the organ words in
    its name and its colors.toml comment; a material named by neither (Eustoma's cultivar
    colours, ``<part>_default``) is a petal: most of a flower model's surface is."""
    text = f"{name} {comment}".lower()
    for kind, words in ORGANS:
        if any(w in text for w in words):
            return kind
    return "petal"


def srgb_to_linear(rgb):
    """sRGB 0..1 -> linear (IEC 61966-2-1), as canopy-export writes its colours."""
    return tuple(c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in rgb)
