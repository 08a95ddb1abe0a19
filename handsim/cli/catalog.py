"""``handsim catalog``: list the catalogue's objects with their size and mass."""

from __future__ import annotations

import argparse

from handsim.cli._common import Commands


def _run(args: argparse.Namespace) -> int:
    # lazy: the catalogue table, only for this command
    from handsim.builders.catalog import entries

    rows = [
        (
            e.name,
            "" if e.graspdb_id is None else str(e.graspdb_id),
            e.source,
            "from density" if e.mass_kg is None else f"{e.mass_kg * 1000:.0f} g",
            e.size,
        )
        for e in entries()
    ]
    header = ("name", "id", "source", "mass", "size")
    widths = [max(len(r[i]) for r in (header, *rows)) for i in range(4)]
    for row in (header, *rows):
        print("  ".join(c.ljust(w) for c, w in zip(row[:4], widths, strict=True)) + "  " + row[4])
    print(
        "\nBuild one with `handsim build object NAME -o obj.xml`; GraspDB14 ids are those of the report's "
        "Table 4.1. ARCTIC templates: pass the template folder instead of a name."
    )
    return 0


def register(commands: Commands) -> None:
    """Add the ``catalog`` command."""
    catalog = commands.add_parser(
        "catalog",
        help="list the object catalogue (GraspDB14 objects, bundled Tzionas objects)",
        description="List every catalogue object with its GraspDB14 id, size and mass.",
    )
    catalog.set_defaults(func=_run)
