"""The add-on's sidebar panel as its draw() code lays it out: a diagram, not a screenshot.

``bpy`` as a module has no window to take a screenshot of. This script loads
``blender/inflo_blender`` with a stand-in ``bpy`` (only what the module needs to load), calls
``VIEW3D_PT_inflo.draw`` with a layout that records what it is asked to draw (properties, rows,
operators, labels, in order) on the project's real state (its species and their titles,
``build/<species>/quality.txt``), and draws that list as a sidebar in Blender's dark theme with
Pillow (inflo's ``.venv``; no Blender needed)::

    .venv/bin/python blender/draw_panel.py [--species sunflower] [--quality final] [-o docs/blender/panel.png]
"""
from __future__ import annotations

import argparse
import importlib
import sys
import types
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


# ------------------------------------------------------------------ a stand-in bpy, and recording

class Prop:
    """What ``bpy.props.XProperty(...)`` was called with."""

    def __init__(self, kind, **kw):
        self.kind, self.kw = kind, kw


def stand_in_bpy():
    bpy = types.ModuleType("bpy")
    bpy.types = types.SimpleNamespace(AddonPreferences=object, PropertyGroup=object, Operator=object,
                                      Panel=object, TOPBAR_MT_file_import=None, Scene=object)
    bpy.props = types.ModuleType("bpy.props")
    for kind in ("Bool", "Enum", "Pointer", "String", "Int", "Float"):
        setattr(bpy.props, f"{kind}Property", lambda _k=kind, **kw: Prop(_k, **kw))
    bpy.path = types.SimpleNamespace(abspath=lambda p: p)
    bpy.app = types.SimpleNamespace(background=True)
    bpy.utils = types.SimpleNamespace(register_class=lambda c: None, unregister_class=lambda c: None)
    bpy.context = types.SimpleNamespace(scene=None, preferences=types.SimpleNamespace(addons={}))
    mathutils = types.ModuleType("mathutils")
    mathutils.Vector = tuple
    return bpy, mathutils


def load_addon():
    """blender/inflo_blender with the stand-in bpy (sys.modules restored afterwards)."""
    bpy, mathutils = stand_in_bpy()
    saved = {k: sys.modules.get(k) for k in ("bpy", "bpy.props", "mathutils")}
    sys.modules.update({"bpy": bpy, "bpy.props": bpy.props, "mathutils": mathutils})
    sys.path.insert(0, str(HERE))
    try:
        for k in [k for k in sys.modules if k == "inflo_blender" or k.startswith("inflo_blender.")]:
            del sys.modules[k]
        addon = importlib.import_module("inflo_blender")
    finally:
        sys.path.remove(str(HERE))
        for k in [k for k in sys.modules if k == "inflo_blender" or k.startswith("inflo_blender.")]:
            del sys.modules[k]  # the module object stays with us; a real import later gets a fresh one
        for k, v in saved.items():
            if v is None:
                sys.modules.pop(k, None)
            else:
                sys.modules[k] = v
    return addon, bpy


class Layout:
    """Records the calls of a panel's draw(): ``items`` in order, rows, columns and boxes nested."""

    def __init__(self, kind="layout", align=False):
        self.kind, self.align, self.enabled, self.items = kind, align, True, []

    def _child(self, kind, align=False):
        child = Layout(kind, align)
        self.items.append(child)
        return child

    def row(self, align=False):
        return self._child("row", align)

    def column(self, align=False):
        return self._child("column", align)

    def box(self):
        return self._child("box")

    def label(self, text="", icon="NONE"):
        self.items.append({"type": "label", "text": text, "icon": icon})

    def prop(self, data, name, text=None, expand=False, icon="NONE"):
        p = getattr(type(data), "__annotations__", {}).get(name)
        kw = p.kw if isinstance(p, Prop) else {}
        value = getattr(data, name)
        item = {"type": "prop", "name": name, "label": kw.get("name", name) if text is None else text,
                "kind": p.kind if isinstance(p, Prop) else "String", "value": value, "expand": expand,
                "subtype": kw.get("subtype", "")}
        items = kw.get("items")
        if callable(items):
            items = items(data, _context)
        if items:
            item["items"] = [(i[0], i[1]) for i in items]
        self.items.append(item)

    def operator(self, idname, text="", icon="NONE"):
        op = types.SimpleNamespace()
        self.items.append({"type": "operator", "idname": idname, "text": text, "icon": icon, "enabled": True})
        return op

    def tree(self) -> list:
        """The recorded items as plain data: nested layouts are ``{"type": kind, "enabled", "items"}``."""
        return [{"type": i.kind, "enabled": i.enabled, "items": i.tree()} if isinstance(i, Layout) else i
                for i in self.items]


_context = None


def record(project: Path, species: str, quality: str = "final", scope: str = "usd") -> list:
    """The panel's draw() on a project: the list of what it draws (:meth:`Layout.tree`)."""
    global _context
    addon, bpy = load_addon()
    settings = addon.InfloSettings()
    settings.project, settings.species, settings.quality, settings.scope = str(project), species, quality, scope
    _context = types.SimpleNamespace(scene=types.SimpleNamespace(inflo=settings))
    bpy.context.scene = _context.scene
    panel = addon.VIEW3D_PT_inflo()
    panel.layout = Layout()
    panel.draw(_context)
    return panel.layout.tree()


# ------------------------------------------------------------------------------------- drawing

THEME = {"region": (48, 48, 48), "panel": (61, 61, 61), "header": (61, 61, 61), "text": (230, 230, 230),
         "dim": (150, 150, 150), "field": (29, 29, 29), "menu": (40, 40, 40), "button": (84, 84, 84),
         "selected": (71, 114, 179), "tab": (36, 36, 36), "outline": (24, 24, 24), "box": (53, 53, 53)}
ICONS = {"PLAY": "\u25b6", "IMPORT": "\u2193", "INFO": "i", "CHECKMARK": "\u2713", "ERROR": "!",
         "SORTTIME": "\u231b"}


def draw(tree: list, out: Path, width: int = 330, scale: int = 2, path_text: str | None = None) -> None:
    from PIL import Image, ImageDraw, ImageFont

    def font(size):
        for name in ("DejaVuSans.ttf", "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"):
            try:
                return ImageFont.truetype(name, size * scale)
            except OSError:
                pass
        return ImageFont.load_default()

    f, small = font(11), font(9)
    s = scale
    pad, rowh, gap = 10 * s, 20 * s, 4 * s
    tab = 22 * s
    W = width * s

    def text_in(d, box, text, colour, align="left", icon="NONE"):
        x0, y0, x1, y1 = box
        iw = 16 * s if icon != "NONE" else 0
        x = x0 + 6 * s
        while text and d.textlength(text, font=f) > x1 - x - iw - 4 * s:
            text = text[:-2] + "\u2026"
        if align == "center":
            x = max(x, (x0 + x1 - iw - d.textlength(text, font=f)) / 2)
        if icon != "NONE":
            d.text((x, (y0 + y1) / 2), ICONS.get(icon, "\u2022"), fill=colour, font=f, anchor="lm")
        d.text((x + iw, (y0 + y1) / 2), text, fill=colour, font=f, anchor="lm")

    def widget(d, box, colour, enabled=True):
        fill = colour if enabled else tuple(int(c * 0.8 + 48 * 0.2) for c in colour)
        d.rounded_rectangle(box, radius=4 * s, fill=fill, outline=THEME["outline"], width=max(1, s // 2))

    def item_height(it):
        if it["type"] in ("row", "column", "box"):
            inner = sum(item_height(c) + gap for c in it["items"]) - gap if it["items"] else 0
            if it["type"] == "row" and it["items"]:
                inner = max(item_height(c) for c in it["items"])
            return inner + (2 * gap if it["type"] == "box" else 0)
        return rowh

    def draw_item(d, it, x0, x1, y, enabled=True):
        en = enabled and it.get("enabled", True)
        tc = THEME["text"] if en else THEME["dim"]
        if it["type"] in ("row", "column", "box"):
            if it["type"] == "box":
                d.rounded_rectangle((x0, y, x1, y + item_height(it)), radius=4 * s, fill=THEME["box"],
                                    outline=THEME["outline"])
                x0, x1, y = x0 + gap, x1 - gap, y + gap
            kids = it["items"]
            if it["type"] == "row" and kids:
                w = (x1 - x0) / len(kids)
                for k, c in enumerate(kids):
                    draw_item(d, c, x0 + k * w, x0 + (k + 1) * w, y, en)
            else:
                for c in kids:
                    draw_item(d, c, x0, x1, y, en)
                    y += item_height(c) + gap
            return
        box = (x0, y, x1, y + rowh)
        if it["type"] == "label":
            text_in(d, box, it["text"], tc, icon=it["icon"])
        elif it["type"] == "operator":
            widget(d, box, THEME["button"], en)
            text_in(d, box, it["text"], tc, align="center", icon=it["icon"])
        elif it["type"] == "prop" and it.get("expand") and it.get("items"):
            n = len(it["items"])
            w = (x1 - x0) / n
            for k, (ident, name) in enumerate(it["items"]):
                b = (x0 + k * w, y, x0 + (k + 1) * w, y + rowh)
                widget(d, b, THEME["selected"] if ident == it["value"] else THEME["menu"], en)
                text_in(d, b, name, tc, align="center")
        elif it["type"] == "prop":
            split = x0 + (x1 - x0) * 0.36
            text_in(d, (x0, y, split, y + rowh), it["label"], tc)
            fb = (split, y, x1, y + rowh)
            if it["kind"] == "Enum":
                widget(d, fb, THEME["menu"], en)
                names = dict(it.get("items", []))
                text_in(d, (fb[0], y, fb[2] - 14 * s, y + rowh), names.get(it["value"], str(it["value"])), tc)
                d.text((fb[2] - 8 * s, y + rowh / 2), "\u25be", fill=tc, font=f, anchor="mm")
            else:
                widget(d, fb, THEME["field"], en)
                value = str(it["value"]) if path_text is None or it.get("subtype") != "DIR_PATH" else path_text
                text_in(d, (fb[0], y, fb[2] - 20 * s, y + rowh), value, tc)
                if it.get("subtype") == "DIR_PATH":  # the file-browser button: a small folder
                    fx, fy = fb[2] - 16 * s, y + rowh / 2
                    d.rectangle((fx, fy - 3 * s, fx + 10 * s, fy + 4 * s), outline=tc, width=max(1, s // 2))
                    d.rectangle((fx, fy - 5 * s, fx + 4 * s, fy - 3 * s), fill=tc)

    body = sum(item_height(i) + gap for i in tree) - gap
    header = 24 * s
    footer = 22 * s
    H = pad + header + pad + body + pad + pad + footer
    img = Image.new("RGB", (W, H), THEME["region"])
    d = ImageDraw.Draw(img)
    px0, px1 = pad, W - tab - pad
    # the panel: header (collapse arrow and its label) over its body
    d.rounded_rectangle((px0, pad, px1, pad + header + pad + body + pad), radius=5 * s, fill=THEME["panel"])
    d.text((px0 + 8 * s, pad + header / 2), "\u25be", fill=THEME["text"], font=f, anchor="lm")
    d.text((px0 + 22 * s, pad + header / 2), "inflo", fill=THEME["text"], font=f, anchor="lm")
    d.line((px0, pad + header, px1, pad + header), fill=THEME["region"], width=s)
    y = pad + header + pad
    for it in tree:
        draw_item(d, it, px0 + pad, px1 - pad, y)
        y += item_height(it) + gap
    # the sidebar's category tabs on its right edge: the add-on's own, selected
    d.rectangle((W - tab, 0, W, H), fill=THEME["tab"])
    tw = int(d.textlength("inflo", font=f)) + 16 * s
    label = Image.new("RGB", (tw, tab - 4 * s), THEME["panel"])
    ImageDraw.Draw(label).text((tw / 2, (tab - 4 * s) / 2), "inflo", fill=THEME["text"], font=f, anchor="mm")
    img.paste(label.rotate(-90, expand=True), (W - tab + 2 * s, pad))
    d.text((W / 2, H - footer / 2), "diagram of VIEW3D_PT_inflo.draw(), not a screenshot", fill=THEME["dim"],
           font=small, anchor="mm")
    out.parent.mkdir(parents=True, exist_ok=True)
    img.save(out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="draw_panel.py", description=__doc__.splitlines()[0])
    p.add_argument("--project", default=str(ROOT), help="the inflo project whose state the panel shows [this one]")
    p.add_argument("--species", default="lily")
    p.add_argument("--quality", choices=("draft", "final"), default="final")
    p.add_argument("--path-text", default="/path/to/inflo/", help="the project folder as shown in the picture")
    p.add_argument("-o", "--output", default=str(ROOT / "docs" / "blender" / "panel.png"))
    args = p.parse_args(argv)
    tree = record(Path(args.project).resolve(), args.species, args.quality)
    draw(tree, Path(args.output), path_text=args.path_text)
    print(f"draw_panel: {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
