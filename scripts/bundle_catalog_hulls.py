"""Decompose the catalogue's concave objects with the default CoACD parameters into the bundled cache.

Run after changing a catalogue mesh, the default parameters, the cache format or the CoACD version:

    python scripts/bundle_catalog_hulls.py

It writes ``handsim/assets/coacd_cache/coacd/<key[:2]>/<key>.npz`` (the same layout as the user cache)
and ``COACD_VERSION``, and removes entries no catalogue object uses any more.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import shutil
import time

from handsim.builders import catalog
from handsim.builders.decompose import decompose
from handsim.builders.decomposition_types import DecompositionParams
from handsim.builders.hull_cache import BUNDLED_CACHE_DIR


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.parse_args()
    params = DecompositionParams()
    keep = set()
    for entry in catalog.entries():
        for part in entry.load().parts:
            if part.primitives:
                continue
            start = time.perf_counter()
            result = decompose(part.mesh, params, cache_dir=BUNDLED_CACHE_DIR, progress=True)
            if result.skipped:
                continue
            keep.add(result.key)
            how = "cached" if result.from_cache else "computed"
            print(
                f"{entry.name:16s} {part.name:8s} {len(result.hulls):2d} hulls, "
                f"CoACD {result.coacd_seconds:6.1f} s ({how} in {time.perf_counter() - start:.1f} s)"
            )
    (BUNDLED_CACHE_DIR / "COACD_VERSION").write_text(importlib.metadata.version("coacd") + "\n")
    for path in (BUNDLED_CACHE_DIR / "coacd").glob("*/*.npz"):
        if path.stem not in keep:
            path.unlink()
            print(f"removed stale {path}")
    for folder in (BUNDLED_CACHE_DIR / "coacd").glob("*"):
        if folder.is_dir() and not any(folder.iterdir()):
            shutil.rmtree(folder)


if __name__ == "__main__":
    main()
