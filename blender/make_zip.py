"""Write the Blender add-on's zip: ``python3 blender/make_zip.py -o build/inflo_blender.zip``.

The zip holds one folder, ``inflo_blender/`` (``__init__.py`` with ``bl_info`` for Blender's
"Install legacy Add-on" and older versions, ``blender_manifest.toml`` for 4.2+'s extensions,
which accept an archive whose files are in one folder). Standard library only; the same bytes
for the same sources (fixed timestamps, sorted names), written to a temporary name and renamed.
"""
import argparse
import os
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "inflo_blender"


def files(source: Path = SOURCE) -> list[Path]:
    return sorted(p for p in source.rglob("*")
                  if p.is_file() and "__pycache__" not in p.parts and p.suffix in (".py", ".toml"))


def write_zip(out: Path, source: Path = SOURCE) -> list[str]:
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.part")
    names = []
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for p in files(source):
            name = f"{source.name}/{p.relative_to(source).as_posix()}"
            info = zipfile.ZipInfo(name, date_time=(2026, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, p.read_bytes())
            names.append(name)
    os.replace(tmp, out)
    return names


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", type=Path, required=True)
    args = ap.parse_args()
    names = write_zip(args.output)
    print(f"{args.output}: {', '.join(names)}")


if __name__ == "__main__":
    main()
