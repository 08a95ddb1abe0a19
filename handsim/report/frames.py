"""Rendered frames of a trial, read back for embedding: PNG bytes as ``data:`` URIs, hashes checked."""

from __future__ import annotations

import base64
import hashlib
from dataclasses import dataclass
from pathlib import Path

from handsim.runner.png import PNG_SIGNATURE

DEFAULT_EMBED_BUDGET = 32 * 1024 * 1024  # bytes of PNG embedded in one HTML file at most


@dataclass(frozen=True)
class FrameImage:
    """One rendered frame of a trial.

    Attributes:
        frame: Frame index in the trial.
        time_s: Trajectory time, s (None if the record has none).
        path: Path relative to the run folder, as recorded.
        data_uri: ``data:image/png;base64,…`` when embedded, else None.
        problem: Why the frame is not embedded or cannot be trusted (missing file, not a PNG, hash
            mismatch, over the size budget), else None.
    """

    frame: int | None
    time_s: float | None
    path: str
    data_uri: str | None
    problem: str | None


class FrameBudget:
    """Bytes of PNG still allowed into one HTML file (a run of thousands of trials stays openable)."""

    def __init__(self, limit: int = DEFAULT_EMBED_BUDGET) -> None:
        self.left = limit

    def take(self, size: int) -> bool:
        """Reserve ``size`` bytes if they fit."""
        if size > self.left:
            return False
        self.left -= size
        return True


def load_frames(record: dict, out_dir: Path, budget: FrameBudget) -> list[FrameImage]:
    """The record's rendered frames, embedded while ``budget`` allows.

    Args:
        record: A trial record (its ``renders``: frame, time_s, path relative to ``out_dir``, sha256).
        out_dir: The run folder.
        budget: Embedding budget shared by the whole report (taken in the order frames are loaded).

    Returns:
        One entry per render, in the record's order; a missing or altered file is reported in
        ``problem``, not raised.
    """
    images = []
    for render in record.get("renders") or []:
        rel = str(render.get("path") or "")
        frame, time_s = render.get("frame"), render.get("time_s")
        path = out_dir / rel
        if not rel or not path.is_file():
            images.append(FrameImage(frame, time_s, rel, None, f"file {rel or '(no path)'} is missing"))
            continue
        data = path.read_bytes()
        problem = None
        if not data.startswith(PNG_SIGNATURE):
            images.append(FrameImage(frame, time_s, rel, None, f"{rel} is not a PNG file"))
            continue
        expected = render.get("sha256")
        if expected and hashlib.sha256(data).hexdigest() != expected:
            problem = f"{rel} does not match the SHA-256 recorded for it (changed after the run)"
        uri = None
        if budget.take(len(data)):
            uri = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
        else:
            problem = problem or "not embedded: the report's image size budget is used up (see the file)"
        images.append(FrameImage(frame, time_s, rel, uri, problem))
    return images
