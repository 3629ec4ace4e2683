"""URDF text of the casting robot: an xArm6 (masses, inertias, kinematics, limits) with a rod.

Why generated rather than loaded from pybullet_data: the shipped xarm6 URDF carries mesh
collision shapes that cost time and are never needed (water contact is detected from the hook's
height), and the rod, line and hook must be appended to its flange. The arm's numbers below are
copied from pybullet_data/xarm/xarm6_robot.urdf (UFACTORY's description); the rod, line and hook
numbers are ours (chosen, see README_world.md).
"""

from __future__ import annotations

from dataclasses import dataclass

TWO_PI = 6.28318530718
# (name, parent, origin xyz, origin rpy, lower, upper, effort N m, velocity rad/s) from xarm6.
XARM6_JOINTS: tuple[tuple[str, str, str, str, float, float, float, float], ...] = (
    ("joint1", "link_base", "0 0 0.267", "0 0 0", -TWO_PI, TWO_PI, 50.0, 3.14),
    ("joint2", "link1", "0 0 0", "-1.5708 0 0", -2.059, 2.0944, 50.0, 3.14),
    ("joint3", "link2", "0.0535 -0.2845 0", "0 0 0", -3.927, 0.19198, 32.0, 3.14),
    ("joint4", "link3", "0.0775 0.3425 0", "-1.5708 0 0", -TWO_PI, TWO_PI, 32.0, 3.14),
    ("joint5", "link4", "0 0 0", "1.5708 0 0", -1.69297, 3.14159265359, 32.0, 3.14),
    ("joint6", "link5", "0.076 0.097 0", "-1.5708 0 0", -TWO_PI, TWO_PI, 20.0, 3.14),
)
# (link, mass kg, com xyz, ixx ixy ixz iyy iyz izz) from xarm6.
XARM6_LINKS: tuple[tuple[str, float, str, str], ...] = (
    ("link_base", 2.7, "0.0 0.0 0.09103",
     'ixx="0.00494875" ixy="-3.5E-06" ixz="1.25E-05" iyy="0.00494174" iyz="1.67E-06" '
     'izz="0.002219"'),
    ("link1", 2.16, "-0.002 0.02692 -0.01332",
     'ixx="0.00539427" ixy="1.095E-05" ixz="1.635E-06" iyy="0.0048979" iyz="0.000793" '
     'izz="0.00311573"'),
    ("link2", 1.71, "0.03531 -0.21398 0.03386",
     'ixx="0.0248674" ixy="-0.00430651" ixz="-0.00067797" iyy="0.00485548" iyz="0.00457245" '
     'izz="0.02387827"'),
    ("link3", 1.384, "0.06781 0.10749 0.01457",
     'ixx="0.0053694" ixy="0.0014185" ixz="-0.00092094" iyy="0.0032423" iyz="-0.00169178" '
     'izz="0.00501731"'),
    ("link4", 1.115, "-0.00021 0.02578 -0.02538",
     'ixx="0.00439263" ixy="5.028E-05" ixz="1.374E-05" iyy="0.0040077" iyz="0.00045338" '
     'izz="0.00110321"'),
    ("link5", 1.275, "0.05428 0.01781 0.00543",
     'ixx="0.001202758" ixy="0.000492428" ixz="-0.00039147" iyy="0.0022876" iyz="-1.235E-04" '
     'izz="0.0026866"'),
    ("link6", 0.1096, "0 0.00064 -0.00952",
     'ixx="4.5293E-05" ixy="0" ixz="0" iyy="4.8111E-05" iyz="0" izz="7.9715E-05"'),
)


@dataclass(frozen=True)
class RodSpec:
    """Sizes and masses of rod, line and hook (chosen: a light 1.3 m rod, 0.4 m of line)."""

    handle_length: float = 0.30  # rigid butt clamped in the flange, m
    handle_mass: float = 0.10
    segment_lengths: tuple[float, ...] = (0.55, 0.45)  # flexible sections, butt to tip, m
    # A stiff sea rod: lighter sections or line made pybullet's explicit step blow up at 1/240 s.
    segment_masses: tuple[float, ...] = (0.10, 0.05)
    # One 0.4 m line link: with two 0.2 m links the line whipped at 100-300 rad/s and pybullet's
    # step exploded on 40 % of random casts at 1/240 s.
    line_lengths: tuple[float, ...] = (0.40,)  # line links, m
    line_mass: float = 0.01  # per line link, kg (line with its swivel and sinker)
    hook_mass: float = 0.02  # hook and float, kg


def _rod_inertia(mass: float, length: float) -> str:
    """Thin rod along z about its centre; a floor on izz keeps the spin axis well conditioned."""
    i_perp = mass * length * length / 12.0
    i_axial = i_perp / 10.0
    return f'ixx="{i_perp:.6g}" ixy="0" ixz="0" iyy="{i_perp:.6g}" iyz="0" izz="{i_axial:.6g}"'


def _diagonal_only(inertia: str) -> str:
    """Drop products of inertia: pybullet rejects (zeroes) xarm6's full link2/link3 tensors."""
    for key in ("ixy", "ixz", "iyz"):
        start = inertia.index(f'{key}="')
        end = inertia.index('"', start + len(key) + 2)
        inertia = inertia[:start] + f'{key}="0' + inertia[end:]
    return inertia


def _link(name: str, mass: float, com: str, inertia: str) -> str:
    return (
        f'  <link name="{name}"><inertial><origin xyz="{com}" rpy="0 0 0"/>'
        f'<mass value="{mass:.6g}"/><inertia {inertia}/></inertial></link>\n'
    )


def _joint(name: str, kind: str, parent: str, child: str, xyz: str, rpy: str = "0 0 0",
           axis: str = "0 0 1", limit: str = "") -> str:
    return (
        f'  <joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>{limit}</joint>\n'
    )


def build_urdf(spec: RodSpec = RodSpec()) -> str:
    """The robot: xArm6, then handle, flexible sections (2 passive revolute axes per bend), line."""
    parts = ['<?xml version="1.0"?>\n<robot name="xarm6_fishing_rod">\n']
    for name, mass, com, inertia in XARM6_LINKS:
        parts.append(_link(name, mass, com, _diagonal_only(inertia)))
    for k, (name, parent, xyz, rpy, lo, hi, effort, vel) in enumerate(XARM6_JOINTS):
        limit = f'<limit lower="{lo}" upper="{hi}" effort="{effort}" velocity="{vel}"/>'
        parts.append(_joint(name, "revolute", parent, XARM6_LINKS[k + 1][0], xyz, rpy,
                            limit=limit))
    # Rod along the flange's +z axis.
    parts.append(_link("rod_handle", spec.handle_mass, f"0 0 {spec.handle_length / 2}",
                       _rod_inertia(spec.handle_mass, spec.handle_length)))
    parts.append(_joint("rod_mount", "fixed", "link6", "rod_handle", "0 0 0"))
    parent, offset = "rod_handle", spec.handle_length
    free = '<limit lower="-3.14" upper="3.14" effort="0" velocity="100"/>'
    # Each flexible section is two half-pieces: a hinge about x at its butt, a hinge about y at
    # its middle. Alternating orthogonal hinges let the rod bend in any direction while every
    # body keeps a real mass and inertia (a massless gimbal between two axes blows up).
    for k, (length, mass) in enumerate(zip(spec.segment_lengths, spec.segment_masses,
                                           strict=True)):
        half = length / 2
        for axis_name, axis in (("x", "1 0 0"), ("y", "0 1 0")):
            piece = f"rod_seg{k}_{axis_name}"
            parts.append(_link(piece, mass / 2, f"0 0 {half / 2}", _rod_inertia(mass / 2, half)))
            parts.append(_joint(f"rod_bend{k}_{axis_name}", "revolute", parent, piece,
                                f"0 0 {offset}", axis=axis, limit=free))
            parent, offset = piece, half
    for k, length in enumerate(spec.line_lengths):
        seg = f"line{k}"
        # A spherical joint needs inertia about the link's own axis too (rod notes, pitfall 2).
        i_perp = spec.line_mass * length * length / 12.0
        inertia = (f'ixx="{i_perp:.6g}" ixy="0" ixz="0" iyy="{i_perp:.6g}" iyz="0" '
                   f'izz="{i_perp:.6g}"')
        parts.append(_link(seg, spec.line_mass, f"0 0 {length / 2}", inertia))
        parts.append(_joint(f"line_joint{k}", "spherical", parent, seg, f"0 0 {offset}"))
        parent, offset = seg, length
    r = 0.01  # hook treated as a 1 cm ball for its inertia
    i_ball = 0.4 * spec.hook_mass * r * r
    parts.append(_link("hook", spec.hook_mass, "0 0 0",
                       f'ixx="{i_ball:.6g}" ixy="0" ixz="0" iyy="{i_ball:.6g}" iyz="0" '
                       f'izz="{i_ball:.6g}"'))
    parts.append(_joint("hook_mount", "fixed", parent, "hook", f"0 0 {offset}"))
    parts.append("</robot>\n")
    return "".join(parts)
