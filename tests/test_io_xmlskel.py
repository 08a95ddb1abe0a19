"""GraspDB14 .xmlskel reader: real file, conventions, every promised error, and a property test."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from handsim.errors import FormatError, InputFileError
from handsim.io import read_skeleton
from handsim.io.graspdb.xmlskel import read_xmlskel

JOINT = """<joint><name>{name}</name><id>{id}</id><position>{pos}</position>
<limits><rotx>{rx}</rotx><roty>0 0</roty><rotz>{rz}</rotz></limits>{children}</joint>"""


def _xml(units="<angle>deg</angle><length>mm</length>", body=None):
    if body is None:
        tip = JOINT.format(name="a-tip", id=3, pos="0 -60 0", rx="0 0", rz="0 0", children="")
        mcp = JOINT.format(name="a-mcp", id=2, pos="10 -20 0", rx="0 90", rz="-10 20", children=tip)
        body = JOINT.format(name="root", id=1, pos="0 0 0", rx="-180 180", rz="0 0", children=mcp)
    return f"<skeleton>\n<units>{units}</units>\n{body}\n</skeleton>\n"


def _write(tmp_path, text, name="hand.xmlskel"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_real_graspdb_skeleton_has_25_joints_27_dofs_and_absolute_positions(graspdb_dir):
    skeleton = read_skeleton(graspdb_dir / "default.xmlskel")
    assert skeleton.njoints == 25
    assert skeleton.ndof == 27
    assert skeleton.fingertips == ("th-tip", "if-tip", "mf-tip", "rf-tip", "lf-tip")
    # <position> is absolute: if-pip sits at (27, -145, 0) mm, not parent + offset.
    np.testing.assert_allclose(skeleton.joints[skeleton.joint_index("if-pip")].position, [0.027, -0.145, 0])
    assert skeleton.dofs[skeleton.dof_index("if_mcp_flex")].upper == pytest.approx(math.radians(90))
    assert any("th-tmc roty" in n for n in skeleton.notes)


def test_local_frames_follow_graspdb_fix_llc_rule(graspdb_dir):
    skeleton = read_skeleton(graspdb_dir / "default.xmlskel")
    for joint in skeleton.joints:
        if joint.parent < 0 or joint.name == "th-tmc":
            np.testing.assert_allclose(joint.frame, np.eye(3))
            continue
        v = joint.position - skeleton.joints[joint.parent].position
        v /= np.linalg.norm(v)
        a = math.asin(v[0])  # bones lie in the x/y plane: rotation about z by asin(v_x)
        c, s = math.cos(a), math.sin(a)
        np.testing.assert_allclose(joint.frame, [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-15)
        # local -y runs along the bone
        np.testing.assert_allclose(-joint.frame[:, 1], v, atol=1e-12)


def test_dofs_are_ordered_abduction_outer_flexion_inner(tmp_path):
    skeleton = read_xmlskel(_write(tmp_path, _xml()))
    assert skeleton.dof_names == ("root_flex", "a_mcp_abd", "a_mcp_flex")
    assert skeleton.dofs[1].kind == "abd" and skeleton.dofs[2].kind == "flex"


def test_units_are_converted_from_what_the_file_declares(tmp_path):
    in_m = read_xmlskel(
        _write(
            tmp_path,
            _xml()
            .replace("10 -20 0", "0.01 -0.02 0")
            .replace("0 -60 0", "0 -0.06 0")
            .replace("<length>mm", "<length>m"),
            "m.xmlskel",
        )
    )
    in_mm = read_xmlskel(_write(tmp_path, _xml(), "mm.xmlskel"))
    np.testing.assert_allclose(in_m.rest_positions, in_mm.rest_positions)
    in_rad = read_xmlskel(
        _write(tmp_path, _xml().replace("<angle>deg", "<angle>rad").replace("0 90", "0 1.5"), "rad.xmlskel")
    )
    assert in_rad.dofs[2].upper == 1.5


def test_read_skeleton_raises_error_if_file_is_missing(tmp_path):
    with pytest.raises(InputFileError, match=r"nope\.xmlskel: file not found"):
        read_skeleton(tmp_path / "nope.xmlskel")


def test_read_skeleton_raises_error_if_extension_is_unknown(tmp_path):
    path = _write(tmp_path, "x", "hand.bvh")
    with pytest.raises(InputFileError, match=r"unknown skeleton file type '\.bvh'; handsim reads \.xmlskel"):
        read_skeleton(path)


def test_read_xmlskel_raises_error_if_xml_is_malformed(tmp_path):
    path = _write(tmp_path, _xml().replace("</skeleton>", "</skel>"))
    with pytest.raises(FormatError, match=r"hand\.xmlskel:\d+: malformed XML: mismatched tag"):
        read_xmlskel(path)


def test_read_xmlskel_raises_error_if_joint_has_no_position(tmp_path):
    path = _write(tmp_path, _xml().replace("<position>10 -20 0</position>", ""))
    with pytest.raises(FormatError, match=r"hand\.xmlskel:4 <joint> \[position\]: <joint> has no <position>"):
        read_xmlskel(path)


def test_read_xmlskel_raises_error_if_position_has_wrong_count(tmp_path):
    path = _write(tmp_path, _xml().replace("10 -20 0", "10 -20"))
    with pytest.raises(FormatError, match=r"<position> \[position\]: joint 'a-mcp': expected 3 numbers"):
        read_xmlskel(path)


def test_read_xmlskel_raises_error_if_joint_names_repeat(tmp_path):
    path = _write(tmp_path, _xml().replace("a-tip", "a-mcp"))
    message = r"\[name\]: duplicate joint name 'a-mcp' \(first defined on line 4\)"
    with pytest.raises(FormatError, match=message):
        read_xmlskel(path)


def test_read_xmlskel_raises_error_if_joint_ids_repeat(tmp_path):
    path = _write(tmp_path, _xml().replace("<id>3</id>", "<id>2</id>"))
    with pytest.raises(FormatError, match=r"\[id\]: duplicate joint id 2 \('a-tip' and 'a-mcp'"):
        read_xmlskel(path)


def test_read_xmlskel_raises_error_if_min_exceeds_max(tmp_path):
    path = _write(tmp_path, _xml().replace("<rotx>0 90</rotx>", "<rotx>90 0</rotx>"))
    with pytest.raises(FormatError, match=r":5 <limits/rotx> \[rotx\]: joint 'a-mcp': min 90 > max 0"):
        read_xmlskel(path)


def test_read_xmlskel_raises_error_if_limit_is_not_a_number(tmp_path):
    path = _write(tmp_path, _xml().replace("<rotx>0 90</rotx>", "<rotx>0 ninety</rotx>"))
    with pytest.raises(FormatError, match=r":5 \[rotx max\]: expected a number, got 'ninety'"):
        read_xmlskel(path)


@pytest.mark.parametrize(("tag", "value"), [("angle", "grad"), ("length", "cm"), ("length", "")])
def test_read_xmlskel_raises_error_if_units_are_not_supported(tmp_path, tag, value):
    units = "<angle>deg</angle><length>mm</length>".replace(
        f"<{tag}>{'deg' if tag == 'angle' else 'mm'}</{tag}>", f"<{tag}>{value}</{tag}>"
    )
    path = _write(tmp_path, _xml(units=units))
    with pytest.raises(FormatError, match=rf"<units/{tag}> \[{tag}\]: unit '{value}' is not supported"):
        read_xmlskel(path)


def test_read_xmlskel_raises_error_if_units_are_missing(tmp_path):
    path = _write(tmp_path, _xml().replace("<units><angle>deg</angle><length>mm</length></units>", ""))
    with pytest.raises(FormatError, match=r"missing <units>; expected <angle>deg\|rad</angle>"):
        read_xmlskel(path)


def test_read_xmlskel_raises_error_if_bone_has_zero_length(tmp_path):
    path = _write(tmp_path, _xml().replace("0 -60 0", "10 -20 0"))
    with pytest.raises(FormatError, match=r"joint 'a-tip' sits on its parent 'a-mcp' \(zero-length bone\)"):
        read_xmlskel(path)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-40, 40), st.floats(5, 60), st.floats(-30, 0), st.floats(0, 120)),
        min_size=1,
        max_size=5,
    )
)
def test_chains_round_trip_through_xmlskel(tmp_path_factory, segments):
    # A random finger chain: each joint dx mm sideways and dy mm further along -y, with a flexion range.
    tmp = tmp_path_factory.mktemp("prop")
    x, y, nodes, expected = 0.0, 0.0, "", [(0.0, 0.0)]
    points = []
    for dx, dy, lo, hi in segments:
        x, y = x + dx, y - dy
        points.append((x, y, lo, hi))
        expected.append((x, y))
    for k, (px, py, lo, hi) in reversed(list(enumerate(points))):
        nodes = JOINT.format(
            name=f"j{k}", id=k + 2, pos=f"{px!r} {py!r} 0", rx=f"{lo!r} {hi!r}", rz="0 0", children=nodes
        )
    text = _xml(body=JOINT.format(name="root", id=1, pos="0 0 0", rx="0 0", rz="0 0", children=nodes))
    skeleton = read_xmlskel(_write(tmp, text))
    np.testing.assert_allclose(skeleton.rest_positions[:, :2], np.array(expected) / 1000.0, atol=1e-12)
    dofs = [(lo, hi) for (_, _, lo, hi) in points if lo != hi]
    np.testing.assert_allclose(skeleton.limits, np.radians(dofs).reshape(-1, 2))
    np.testing.assert_allclose(
        skeleton.forward_kinematics(skeleton.zero_pose()).positions, skeleton.rest_positions, atol=1e-15
    )
