"""``handsim build hand|object|scene``: build MuJoCo models and write them as MJCF."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

from handsim.cli._common import (
    Commands,
    add_force,
    add_hand_size,
    add_object_mass_options,
    add_ranged_float,
    output_file,
    positive_number,
    usage_error,
    write_text,
)
from handsim.datatypes.physical_ranges import HAND_MASS

HAND_POS_LIMIT_M = 1.0
"""Largest distance of the hand's root from the table top's centre along each axis, m: the table is
1 m × 0.7 m with its top at z = 0 and the floor 0.75 m below, and an arm reaches about 0.7 m; a hand farther
away grasps nothing on it (1e6 is a unit or typing error)."""


def hand_coordinate(text: str) -> float:
    """An argparse type: one coordinate of ``--hand-pos``, metres, within :data:`HAND_POS_LIMIT_M` of 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of metres, got {text!r}") from None
    if not (math.isfinite(value) and abs(value) <= HAND_POS_LIMIT_M):
        raise argparse.ArgumentTypeError(
            f"expected a coordinate within ±{HAND_POS_LIMIT_M:g} m of the table top's centre (the table is "
            f"1 m × 0.7 m, its top at z = 0), got {text}"
        )
    return value


def _hand_spec(skeleton_path: str | None, args: argparse.Namespace):
    # lazy: the hand builder (MuJoCo, SciPy), only to build a hand
    from handsim.builders import build_hand, default_hand
    from handsim.io import read_skeleton

    force = args.force
    if skeleton_path is None:
        return default_hand(args.hand_length, args.hand_breadth, mass=args.hand_mass, force=force), None
    skeleton = read_skeleton(skeleton_path)
    return build_hand(skeleton, mass=args.hand_mass, collision=args.collision, force=force), skeleton


def _print_model(spec) -> None:
    # lazy: MuJoCo, only once a model is built
    from handsim.sim import compile_spec, summarize

    for line in summarize(compile_spec(spec)).lines():
        print(line)


def _build_hand(args: argparse.Namespace) -> int:
    if args.skeleton is not None and args.default:
        return usage_error("build hand", "give a SKELETON file or --default, not both")
    if args.skeleton is None and not args.default:
        return usage_error("build hand", "give a SKELETON file, or --default for the parametric hand")
    spec, skeleton = _hand_spec(args.skeleton, args)
    if skeleton is not None:
        print(f"skeleton   {skeleton.source} ({skeleton.njoints} joints, {skeleton.ndof} DoFs)")
        for note in skeleton.notes:
            print(f"note       {note}")
    _print_model(spec)
    if args.output is not None:
        print(f"wrote      {write_text(args.output, spec.to_xml())}")
    return 0


def _decomposition_param(name: str, convert: type) -> Callable[[str], float | int]:
    """An argparse type for a field of :class:`~handsim.builders.decomposition_types.DecompositionParams`."""

    def parse(text: str) -> float | int:
        # lazy: the builders (trimesh, SciPy) are slow to import, and --help must not wait
        from handsim.builders.decomposition_types import DecompositionParams

        try:
            value = convert(text)
        except ValueError:
            kind = "a whole number" if convert is int else "a number"
            raise argparse.ArgumentTypeError(f"expected {kind}, got {text!r}") from None
        try:
            DecompositionParams(**{name: value})
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return value

    return parse


def _decomposition_params(args: argparse.Namespace):
    # lazy: trimesh and SciPy (the decomposer), only to build objects
    from handsim.builders.decomposition_types import DecompositionParams

    return DecompositionParams(
        threshold=args.threshold, max_convex_hull=args.max_hulls, timeout_s=args.timeout
    )


def _prepare(what: str, args: argparse.Namespace):
    # lazy: the object builder (MuJoCo, trimesh), only to build objects
    from handsim.builders.catalog import resolve
    from handsim.builders.objects import prepare_object

    model = resolve(what, units=args.units, density=args.density, mass=args.mass, force=args.force)
    return prepare_object(
        model,
        _decomposition_params(args),
        cache_dir=args.cache_dir,
        use_cache=not args.no_cache,
        progress=True,
        force=args.force,
    )


def _print_object(prepared) -> None:
    model = prepared.model
    print(f"object     {model.name}  ({model.source})")
    for part in model.parts:
        props = prepared.mass_properties[part.name]
        d = prepared.decompositions.get(part.name)
        if part.primitives:
            collision = f"{len(part.primitives)} primitives ({', '.join(p.kind for p in part.primitives)})"
        elif d.skipped:
            collision = f"1 hull ({d.skipped})"
        else:
            origin = "cached" if d.from_cache else "computed"
            collision = f"{len(d.hulls)} hulls ({origin}; CoACD {d.coacd_seconds:.1f} s)"
        size = " × ".join(f"{e * 1000:.0f}" for e in part.mesh.extent)
        print(
            f"part       {part.name}: {size} mm, {props.volume * 1e6:.1f} cm³, {_grams(props.mass)}; "
            f"collision {collision}"
        )
    if model.hinge is not None:
        h = model.hinge
        limits = "unlimited" if h.range is None else f"{h.range[0]:.3f} .. {h.range[1]:.3f} rad"
        print(f"hinge      axis {tuple(round(a, 4) for a in h.axis)} through {h.pos} m, {limits}")
    print(f"mass       {_grams(prepared.total_mass)}")
    for note in (*model.notes, *prepared.notes):
        print(f"note       {note}")


def _grams(kg: float) -> str:
    """A mass in grams to 0.1 g, with three significant digits below 1 g (never a bare "0.0 g")."""
    grams = kg * 1000
    return f"{grams:.1f} g" if grams >= 1 else f"{grams:.3g} g"


def _build_object(args: argparse.Namespace) -> int:
    # lazy: the object builder (MuJoCo, trimesh), only to build objects
    from handsim.builders.objects import object_spec

    prepared = _prepare(args.object, args)
    _print_object(prepared)
    spec = object_spec(prepared)
    _print_model(spec)
    if args.output is not None:
        print(f"wrote      {write_text(args.output, spec.to_xml())}")
    return 0


def _build_scene(args: argparse.Namespace) -> int:
    # lazy: the object builder (MuJoCo, trimesh), only to build objects
    from handsim.builders.objects import object_spec
    from handsim.builders.scene import build_scene

    hand = None
    if not args.no_hand:
        hand, _ = _hand_spec(None if args.hand == "default" else args.hand, args)
    objects = []
    for what in args.object:
        prepared = _prepare(what, args)
        _print_object(prepared)
        objects.append(object_spec(prepared))
    spec = build_scene(hand, objects, hand_pos=args.hand_pos, table=not args.no_table)
    _print_model(spec)
    if args.output is not None:
        print(f"wrote      {write_text(args.output, spec.to_xml())}")
    return 0


def _add_object_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--units", choices=("m", "mm"), help="units of a mesh file (required for mesh files)")
    add_object_mass_options(parser, forced=True)
    parser.add_argument(
        "--threshold",
        type=_decomposition_param("threshold", float),
        default=0.05,
        help="CoACD concavity threshold (default 0.05; lower = more hulls)",
    )
    parser.add_argument(
        "--max-hulls",
        type=_decomposition_param("max_convex_hull", int),
        default=16,
        help="most convex hulls per part (default 16; -1: no limit)",
    )
    parser.add_argument(
        "--timeout",
        type=_decomposition_param("timeout_s", float),
        default=600.0,
        metavar="S",
        help="CoACD time limit per part",
    )
    parser.add_argument(
        "--cache-dir", metavar="DIR", help="decomposition cache (default: the user cache dir)"
    )
    parser.add_argument(
        "--no-cache", action="store_true", help="neither read nor write the decomposition cache"
    )


def register(commands: Commands) -> None:
    """Add the ``build`` command and its ``hand``, ``object`` and ``scene`` kinds."""
    build = commands.add_parser(
        "build",
        help="build MuJoCo models (MJCF): hands, objects, scenes",
        description="Build MuJoCo models, print their summary and write them as MJCF with -o.",
    )
    kinds = build.add_subparsers(dest="kind", metavar="KIND", required=True)

    hand = kinds.add_parser(
        "hand",
        help="a hand from a skeleton file or the parametric default",
        description="Build a position-controlled hand from a GraspDB14 .xmlskel or a Tzionas .SKEL "
        "(with .LIMITS, and optionally .MOTION/.OFF/.SKIN/.VOI beside it), or the parametric default hand "
        "(--default). Prints bodies, DoFs, actuators, mass and bounding box; writes MJCF with -o.",
    )
    hand.add_argument("skeleton", nargs="?", metavar="SKELETON_FILE", help=".xmlskel or .SKEL file")
    hand.add_argument("--default", action="store_true", help="use the parametric default hand")
    _add_hand_options(hand, "--mass")
    add_force(hand)
    hand.add_argument(
        "-o", "--output", type=output_file, metavar="XML", help="write the model as MJCF to this file"
    )
    hand.set_defaults(func=_build_hand)

    obj = kinds.add_parser(
        "object",
        help="an object from the catalogue, a mesh file, an ARCTIC template or a Tzionas .SKEL",
        description="Build a free-floating object: convex hulls from CoACD (cached by content; convex "
        "meshes and primitives skip it), a visual mesh, and mass and inertia from the watertight mesh and "
        "a density. Objects: a catalogue name (see `handsim catalog`), a mesh file (.obj/.off/.stl/.ply, "
        "give --units), an ARCTIC template folder, or a Tzionas object .SKEL.",
    )
    obj.add_argument("object", metavar="MESH_OR_CATALOG_NAME")
    _add_object_options(obj)
    add_force(obj)
    obj.add_argument(
        "-o", "--output", type=output_file, metavar="XML", help="write the model as MJCF to this file"
    )
    obj.set_defaults(func=_build_object)

    scene = kinds.add_parser(
        "scene",
        help="a hand and objects on a table",
        description="Build a grasping scene: the hand (prefix hand/) and objects (prefix obj/, or obj0/, "
        "obj1/ … for several) resting on a table whose top is z = 0, a floor, lights and cameras.",
    )
    scene.add_argument(
        "--hand", default="default", metavar="SKELETON_FILE", help="skeleton file, or 'default' (the default)"
    )
    scene.add_argument("--no-hand", action="store_true", help="objects only")
    _add_hand_options(scene, "--hand-mass")  # --mass is the object's
    scene.add_argument(
        "--hand-pos", type=hand_coordinate, nargs=3, default=(0.0, 0.0, 0.12), metavar=("X", "Y", "Z"),
        help=f"position of the hand's root, metres, each within ±{HAND_POS_LIMIT_M:g} (default 0 0 0.12)",
    )  # fmt: skip
    scene.add_argument(
        "--object", action="append", default=[], metavar="MESH_OR_CATALOG_NAME", help="an object (repeatable)"
    )
    _add_object_options(scene)
    add_force(scene)
    scene.add_argument("--no-table", action="store_true", help="no table and floor")
    scene.add_argument(
        "-o", "--output", type=output_file, metavar="XML", help="write the model as MJCF to this file"
    )
    scene.set_defaults(func=_build_scene)


def _add_hand_options(parser: argparse.ArgumentParser, mass_flag: str) -> None:
    add_hand_size(parser)
    parser.add_argument(
        "--hand-breadth",
        type=positive_number,
        default=None,
        metavar="M",
        help="parametric hand: breadth across the metacarpals in metres (default 0.45 × length)",
    )
    add_ranged_float(
        parser, parser, mass_flag, HAND_MASS, dest="hand_mass", default=None, metavar="KG",
        help="whole-hand mass in kg (default: 0.45 kg scaled with the cube of hand length), "
        f"{HAND_MASS.describe()} without --force",
    )  # fmt: skip
    parser.add_argument(
        "--collision",
        choices=("capsules", "mesh"),
        default="capsules",
        help="collision shapes: capsules + palm (default) or per-bone hulls of the skinned mesh",
    )
