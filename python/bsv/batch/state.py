"""What a batch remembers between runs: the parameters' key and the journal of finished items.

The journal ``DIR/batch.jsonl`` gets one JSON line per finished item (done or failed) the moment its
result reaches the client, flushed and synced: an interrupted batch (Ctrl-C, a killed client, a lost
node) keeps every item finished before, and the same command continues with the rest. The last line of
an item wins; a torn last line (the client killed while writing) is ignored.

An item is skipped when its last record has the same input hash (:func:`bsv.batch.items.input_hash`) and
the same parameters key (:func:`params_key`: what is computed, the registration parameters and the bsv
version, so a software update re-processes everything) and either succeeded (and its output folder is
still there) or failed (unless ``--rerun-failed``).
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

#: The journal file in the output folder.
JOURNAL = "batch.jsonl"
#: What a batch computes per item: the volumes (fitted.ply, volumes.json), also the one-page report, or
#: also the body-segment inertial parameters (bsip.json, bsip.csv, model.osim; :func:`bsv.bsip`).
WHATS = ("volumes", "report", "bsip")


@dataclass(frozen=True)
class Spec:
    """What every item of a batch computes: ``what`` (:data:`WHATS`), the segmentation of capture items
    (``camera`` = MediaPipe, ``oracle`` = the virtual scanner's labels), the body density and the
    registration parameters (keywords of :func:`bsv.register`). Small and picklable: it is shipped
    with every task."""

    what: str = "volumes"
    segmentation: str = "camera"
    density: float = 1000.0
    params: dict[str, Any] = field(default_factory=dict)

    def key(self) -> str:
        """The parameters key (see :func:`params_key`)."""
        return params_key(self)


def params_key(spec: Spec) -> str:
    """SHA-256 (hex, 16 characters) of the spec and the bsv version: equal keys give equal results."""
    from .. import __version__

    doc = json.dumps({"spec": asdict(spec), "bsv": __version__}, sort_keys=True, default=str)
    return hashlib.sha256(doc.encode()).hexdigest()[:16]


def load_journal(out_dir: Path) -> dict[str, dict[str, Any]]:
    """The last record of every item in ``out_dir``'s journal (empty when there is none)."""
    path = out_dir / JOURNAL
    records: dict[str, dict[str, Any]] = {}
    if not path.is_file():
        return records
    with path.open(encoding="utf-8") as fh:
        for line in fh:
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                continue  # a line torn by a killed client: that item runs again
            if isinstance(rec, dict) and isinstance(rec.get("item"), str):
                records[rec["item"]] = rec
    return records


def is_current(record: dict[str, Any] | None, input_hash: str, key: str, out_dir: Path,
               rerun_failed: bool) -> bool:
    """Whether an item with this last ``record`` is skipped (see the module's rule)."""
    if record is None or record.get("input_hash") != input_hash or record.get("params_key") != key:
        return False
    if record.get("status") == "ok":
        return (out_dir / record["item"]).is_dir()
    return not rerun_failed


class Journal:
    """Appends records to ``DIR/batch.jsonl`` (one line each, flushed and synced to disk)."""

    def __init__(self, out_dir: Path) -> None:
        self.path = out_dir / JOURNAL
        self._fh = self.path.open("a", encoding="utf-8")

    def append(self, record: dict[str, Any]) -> None:
        """Writes one record durably."""
        self._fh.write(json.dumps(record, sort_keys=True, default=str) + "\n")
        self._fh.flush()
        os.fsync(self._fh.fileno())

    def close(self) -> None:
        """Closes the file."""
        self._fh.close()


__all__ = ["JOURNAL", "WHATS", "Journal", "Spec", "is_current", "load_journal", "params_key"]
