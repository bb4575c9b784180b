"""The items of a batch: what each input is (a capture folder or a cloud file), its name, and its hash.

``bsv batch INPUTS...``: every INPUT is a capture folder (``<folder>/<camera>/camera.json``, as written by
``bsv capture`` or the virtual scanner), a point-cloud file (PLY, labelled or not), or a manifest (``.csv``
or ``.parquet``) with a ``path`` column and optional ``name`` and ``calibration`` columns; relative paths
in a manifest are relative to the manifest's folder. An item's name (its output folder ``DIR/<name>/``)
is the folder name or the file stem unless the manifest gives one; two items of one name are refused.

The input hash (SHA-256 over the item's files: every file of a capture folder by relative path, and its
calibration file) is what makes a batch resumable: an item is done when a result for the same hash and the
same parameters is recorded (:mod:`bsv.batch.state`).
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from ..errors import BatchInputError

#: Item kinds: a two-camera capture folder (``bsv process``) or a cloud file (registration + volumes).
KINDS = ("capture", "cloud")
#: File suffixes read as point clouds.
CLOUD_SUFFIXES = (".ply",)
#: File suffixes read as manifests.
MANIFEST_SUFFIXES = (".csv", ".parquet")
#: Names in the output folder that belong to the batch itself (no item may take them).
RESERVED_NAMES = ("batch.jsonl", "results.csv", "results.parquet")

_NAME_OK = re.compile(r"[^A-Za-z0-9._-]+")


@dataclass(frozen=True)
class Item:
    """One unit of work: ``kind`` (``capture`` or ``cloud``), ``path`` of the input, ``name`` of its output
    folder, and the calibration file of a capture (default ``<capture>/calibration.json``)."""

    name: str
    kind: str
    path: str
    calibration: str | None = None


def is_capture_folder(path: Path) -> bool:
    """Whether ``path`` is a folder holding at least one ``<camera>/camera.json``."""
    return path.is_dir() and any(path.glob("*/camera.json"))


def safe_name(text: str) -> str:
    """``text`` as an output-folder name: letters, digits, ``.``, ``_`` and ``-`` only, no leading dot."""
    name = _NAME_OK.sub("_", text).lstrip(".")
    return name or "item"


def _item(path: Path, name: str | None, calibration: str | None, where: str) -> Item:
    if path.is_dir():
        if not is_capture_folder(path):
            raise BatchInputError(f"{where}: {path} is a folder without <camera>/camera.json; give capture folders, "
                                  f"cloud files ({', '.join(CLOUD_SUFFIXES)}) or a manifest")
        cal = calibration or str(path / "calibration.json")
        return Item(safe_name(name or path.name), "capture", str(path), cal)
    if not path.exists():
        raise BatchInputError(f"{where}: {path} does not exist")
    if path.suffix.lower() in CLOUD_SUFFIXES:
        return Item(safe_name(name or path.stem), "cloud", str(path))
    raise BatchInputError(f"{where}: {path} is neither a capture folder nor a cloud file "
                          f"({', '.join(CLOUD_SUFFIXES)}) nor a manifest ({', '.join(MANIFEST_SUFFIXES)})")


def read_manifest(path: Path) -> list[Item]:
    """The items of a CSV or Parquet manifest (column ``path``; optional ``name``, ``calibration``)."""
    import pyarrow as pa

    try:
        if path.suffix.lower() == ".csv":
            from pyarrow import csv

            table = csv.read_csv(path, convert_options=csv.ConvertOptions(strings_can_be_null=True))
        else:
            import pyarrow.parquet as pq

            table = pq.read_table(path)
    except (OSError, pa.ArrowInvalid) as exc:
        raise BatchInputError(f"manifest {path} cannot be read: {exc}") from exc
    if "path" not in table.column_names:
        raise BatchInputError(f"manifest {path} has no 'path' column (it has {table.column_names}); add one "
                              "holding each capture folder or cloud file")
    cols = {c: table.column(c).to_pylist() for c in ("path", "name", "calibration") if c in table.column_names}
    items = []
    for row, raw in enumerate(cols["path"]):
        where = f"manifest {path} row {row + 1}"
        if not raw:
            raise BatchInputError(f"{where}: empty path")
        p = Path(str(raw))
        p = p if p.is_absolute() else path.parent / p
        name = cols.get("name", [None] * len(cols["path"]))[row]
        cal = cols.get("calibration", [None] * len(cols["path"]))[row]
        if cal and not Path(str(cal)).is_absolute():
            cal = str(path.parent / str(cal))
        items.append(_item(p, None if name is None else str(name), None if cal is None else str(cal), where))
    return items


def collect_items(inputs: Sequence[str | Path], calibration: str | Path | None = None) -> list[Item]:
    """Every item of ``inputs`` (capture folders, cloud files, manifests), in order; ``calibration``:
    the calibration file of capture items that a manifest does not give one (default: each capture's
    own ``calibration.json``). Raises :class:`bsv.errors.BatchInputError` on an unusable input or two
    items of one name."""
    items: list[Item] = []
    for raw in inputs:
        p = Path(raw)
        if p.is_file() and p.suffix.lower() in MANIFEST_SUFFIXES:
            items += read_manifest(p)
        else:
            it = _item(p, None, None if calibration is None else str(calibration), f"input {raw}")
            items.append(it)
    if not items:
        raise BatchInputError("no inputs: give capture folders, cloud files or a manifest")
    _check_names(items)
    return items


def _check_names(items: Iterable[Item]) -> None:
    seen: dict[str, Item] = {}
    for it in items:
        if it.name in RESERVED_NAMES:
            raise BatchInputError(f"{it.path}: the name {it.name!r} is reserved for the batch's own files; "
                                  "rename the input or give a 'name' column in a manifest")
        if it.name in seen:
            raise BatchInputError(f"{seen[it.name].path} and {it.path} would both write {it.name}/; give them "
                                  "distinct names (a manifest with a 'name' column)")
        seen[it.name] = it


def item_files(item: Item) -> list[Path]:
    """The files an item's result depends on: the cloud file, or every file of the capture folder and its
    calibration file (sorted, so the hash does not depend on the listing order)."""
    p = Path(item.path)
    files = sorted(f for f in p.rglob("*") if f.is_file()) if p.is_dir() else [p]
    if item.calibration and Path(item.calibration).is_file() and Path(item.calibration) not in files:
        files.append(Path(item.calibration))
    return files


def input_hash(item: Item, chunk: int = 1 << 20) -> str:
    """SHA-256 (hex) over the item's kind and files (relative name and bytes of each); a missing
    calibration file is part of the hash as its path, so adding it later makes the item new."""
    h = hashlib.sha256(item.kind.encode())
    root = Path(item.path)
    for f in item_files(item):
        rel = str(f.relative_to(root)) if root.is_dir() and f.is_relative_to(root) else f.name
        h.update(b"\0file\0" + rel.encode() + b"\0")
        with f.open("rb") as fh:
            while block := fh.read(chunk):
                h.update(block)
    if item.calibration and not Path(item.calibration).is_file():
        h.update(b"\0missing-calibration\0" + item.calibration.encode())
    return h.hexdigest()


__all__ = ["CLOUD_SUFFIXES", "KINDS", "MANIFEST_SUFFIXES", "RESERVED_NAMES", "Item", "collect_items",
           "input_hash", "is_capture_folder", "item_files", "read_manifest", "safe_name"]
