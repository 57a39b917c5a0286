"""Writes iiwa14.urdf next to this file: the KUKA LBR iiwa 14 R820 with the same probe tool as lwr4.urdf.

Run `python3 gen_iiwa14.py`. Every number is stated here with where it comes from:
  [K] kinematics: KUKA LBR iiwa 14 R820 data (base to A2 0.36 m, A2 to A4 0.42 m, A4 to A6 0.40 m,
      A6 to flange face 0.126 m; the flange without media flange), with the joint frames (offsets
      split 0.1575 + 0.2025, 0.2045 + 0.2155, 0.1845 + 0.2155, 0.081 + 0.045 m, and each frame's
      rpy) as the ROS/Drake iiwa14 description has them (RobotLocomotion/drake,
      manipulation/models/iiwa_description/urdf/iiwa14_primitive_collision.urdf, BSD-3; the same
      frames as IFL-CAMP/iiwa_stack), so that q = 0 is the arm stretched straight up and every
      joint turns the way the KUKA controller counts it;
  [L] position limits A1/A3/A5 +-170 deg, A2/A4/A6 +-120 deg, A7 +-175 deg; efforts 320, 320, 176,
      176, 110, 40, 40 N m; velocities 85, 85, 100, 75, 130, 135, 135 deg/s: the KUKA LBR iiwa
      brochure's axis table, as quoted in Drake's iiwa_description/README.md and its URDF limits;
  [I] inertials (mass, centre of mass, principal inertia in each link's frame): the values of the
      same Drake URDF. They are NOT identified parameters: Drake's comments give KUKA's CAD masses
      for links 2-7 (3.95, 3.18, 2.74, 1.69, 1.8, 0.31 kg) and the older iiwa_stack estimates
      (4, 3, 2.7, 1.7, 1.8, 0.3 kg) beside the masses it uses (6.35, 3.5, 3.5, 3.5, 1.8, 1.2 kg);
  [C] collisions: the cylinders of the same Drake URDF for links 0-5; links 6 and 7 have meshes
      there, so this generator puts a sphere (r 0.075 m) on link 6 and a cylinder (r 0.045 m,
      0.09 m long) on link 7, sized to cover the wrist housing, an approximation of ours;
  [P] probe: the made-up aluminium probe of gen_lwr4.py (0.2 kg shaft + adapter, 10 mm radius
      spherical tip, 0.11 m from the flange face), the tool the skills touch with.
The flange frame (`iiwa_flange`) is link 7's frame moved 0.045 m along its z axis, as Drake's
`iiwa_link_ee_kuka` (whose rpy pi, pi, pi is the identity). Checked against pinocchio by
tools/check/pinocchio_iiwa14.py and against finite differences by runtime/tests/robot_iiwa14.rs.
"""
import math, os

PI = math.pi
HALF_PI = math.pi / 2

def rad(deg):
    return deg * math.pi / 180.0

def solid_cylinder_z(m, r, h):
    side = m * (3 * r * r + h * h) / 12
    return (side, side, m * r * r / 2)

def num(x):
    s = "%.12g" % x
    return "0" if s in ("0", "-0") else s

def vec(t):
    return " ".join(num(x) for x in t)

# Links: (link, mass kg, centre of mass in link frame, principal inertia kg m^2) [I].
LINKS = [
    ("iiwa_link_0", 5.0, (-0.1, 0, 0.07), (0.05, 0.06, 0.03)),
    ("iiwa_link_1", 5.76, (0, -0.03, 0.12), (0.033, 0.0333, 0.0123)),
    ("iiwa_link_2", 6.35, (0.0003, 0.059, 0.042), (0.0305, 0.0304, 0.011)),
    ("iiwa_link_3", 3.5, (0, 0.03, 0.13), (0.025, 0.0238, 0.0076)),
    ("iiwa_link_4", 3.5, (0, 0.067, 0.034), (0.017, 0.0164, 0.006)),
    ("iiwa_link_5", 3.5, (0.0001, 0.021, 0.076), (0.01, 0.0087, 0.00449)),
    ("iiwa_link_6", 1.8, (0, 0.0006, 0.0004), (0.0049, 0.0047, 0.0036)),
    ("iiwa_link_7", 1.2, (0, 0, 0.02), (0.001, 0.001, 0.001)),
]
# Revolute joints, all about their frame's z axis: (name, parent, child, xyz m [K], rpy rad [K],
# limit deg [L], effort N m [L], velocity deg/s [L]).
JOINTS = [
    ("iiwa_joint_1", "iiwa_link_0", "iiwa_link_1", (0, 0, 0.1575), (0, 0, 0), 170, 320, 85),
    ("iiwa_joint_2", "iiwa_link_1", "iiwa_link_2", (0, 0, 0.2025), (HALF_PI, 0, PI), 120, 320, 85),
    ("iiwa_joint_3", "iiwa_link_2", "iiwa_link_3", (0, 0.2045, 0), (HALF_PI, 0, PI), 170, 176, 100),
    ("iiwa_joint_4", "iiwa_link_3", "iiwa_link_4", (0, 0, 0.2155), (HALF_PI, 0, 0), 120, 176, 75),
    ("iiwa_joint_5", "iiwa_link_4", "iiwa_link_5", (0, 0.1845, 0), (-HALF_PI, PI, 0), 170, 110, 130),
    ("iiwa_joint_6", "iiwa_link_5", "iiwa_link_6", (0, 0, 0.2155), (HALF_PI, 0, 0), 120, 40, 135),
    ("iiwa_joint_7", "iiwa_link_6", "iiwa_link_7", (0, 0.081, 0), (-HALF_PI, PI, 0), 175, 40, 135),
]
FLANGE_Z = 0.045  # [K] link 7 frame to the flange face
# Collision primitives per link: ("sphere", xyz, rpy, radius) or ("cylinder", xyz, rpy, (radius, length)).
COLLISIONS = {
    "iiwa_link_0": [("cylinder", (-0.015, 0, 0.07), (0, 0, 0), (0.139, 0.17))],  # [C]
    "iiwa_link_1": [("cylinder", (0, -0.014, 0.14), (0, 0, 0), (0.101, 0.29))],  # [C]
    "iiwa_link_2": [("cylinder", (0, 0.056, 0.035), (HALF_PI, 0, 0), (0.101, 0.29))],  # [C]
    "iiwa_link_3": [("cylinder", (0, 0.025, 0.137), (0, 0, 0), (0.092, 0.29))],  # [C]
    "iiwa_link_4": [("cylinder", (0, 0.056, 0.025), (HALF_PI, 0, 0), (0.092, 0.25))],  # [C]
    "iiwa_link_5": [("cylinder", (0, 0.03, 0.13), (-0.3, 0, 0), (0.07, 0.29))],  # [C]
    "iiwa_link_6": [("sphere", (0, 0, 0), (0, 0, 0), 0.075)],  # ours
    "iiwa_link_7": [("cylinder", (0, 0, 0), (0, 0, 0), (0.045, 0.09))],  # ours
}
PROBE_MASS, PROBE_LENGTH, PROBE_SHAFT_R, TIP_R = 0.2, 0.1, 0.008, 0.01  # [P]

def inertial(out, m, com, inertia, what):
    out.append('    <inertial>')
    out.append('      <!-- %s, %s kg -->' % (what, num(m)))
    out.append('      <origin xyz="%s" rpy="0 0 0"/>' % vec(com))
    out.append('      <mass value="%s"/>' % num(m))
    out.append('      <inertia ixx="%s" ixy="0" ixz="0" iyy="%s" iyz="0" izz="%s"/>' % tuple(num(i) for i in inertia))
    out.append('    </inertial>')

def collision(out, kind, xyz, rpy, size):
    out.append('    <collision>')
    out.append('      <origin xyz="%s" rpy="%s"/>' % (vec(xyz), vec(rpy)))
    if kind == "sphere":
        out.append('      <geometry><sphere radius="%s"/></geometry>' % num(size))
    else:
        out.append('      <geometry><cylinder radius="%s" length="%s"/></geometry>' % (num(size[0]), num(size[1])))
    out.append('    </collision>')

def fixed_joint(out, name, parent, child, z):
    out.append('  <joint name="%s" type="fixed">' % name)
    out.append('    <origin xyz="0 0 %s" rpy="0 0 0"/>' % num(z))
    out.append('    <parent link="%s"/>' % parent)
    out.append('    <child link="%s"/>' % child)
    out.append('  </joint>')

def main():
    out = ['<?xml version="1.0"?>',
           '<!-- KUKA LBR iiwa 14 R820 with a probe tool. Written by gen_iiwa14.py: see it for every number\'s source.',
           '     Kinematics and limits are the iiwa 14\'s; inertials are Drake\'s model values, not identified ones. -->',
           '<robot name="kuka_iiwa14">',
           '  <link name="world"/>']
    fixed_joint(out, "world_to_base", "world", "iiwa_link_0", 0)
    by_child = {j[2]: j for j in JOINTS}
    for (link, m, com, inertia) in LINKS:
        if link in by_child:
            (name, parent, child, xyz, rpy, lim, effort, vel) = by_child[link]
            out.append('  <joint name="%s" type="revolute">' % name)
            out.append('    <origin xyz="%s" rpy="%s"/>' % (vec(xyz), vec(rpy)))
            out.append('    <parent link="%s"/>' % parent)
            out.append('    <child link="%s"/>' % child)
            out.append('    <axis xyz="0 0 1"/>')
            out.append('    <limit lower="%s" upper="%s" effort="%s" velocity="%s"/>'
                       % (num(-rad(lim)), num(rad(lim)), num(effort), num(rad(vel))))
            out.append('  </joint>')
        out.append('  <link name="%s">' % link)
        what = "fixed base: not part of the dynamics" if link == "iiwa_link_0" else "Drake's iiwa14 model"
        inertial(out, m, com, inertia, what)
        for c in COLLISIONS[link]:
            collision(out, *c)
        out.append('  </link>')
    # The flange face, where the wrist force/torque sensor sits. Massless frame.
    fixed_joint(out, "iiwa_flange_joint", "iiwa_link_7", "iiwa_flange", FLANGE_Z)
    out.append('  <link name="iiwa_flange">')
    inertial(out, 0, (0, 0, 0), (0, 0, 0), "massless frame")
    out.append('  </link>')
    # The probe: a shaft along the flange z axis ending in a spherical tip.
    fixed_joint(out, "probe_joint", "iiwa_flange", "probe", 0)
    out.append('  <link name="probe">')
    inertial(out, PROBE_MASS, (0, 0, PROBE_LENGTH / 2),
             solid_cylinder_z(PROBE_MASS, 0.015, PROBE_LENGTH), "probe shaft and adapter, cylinder r 0.015 h 0.1")
    collision(out, "cylinder", (0, 0, PROBE_LENGTH / 2), (0, 0, 0), (PROBE_SHAFT_R, PROBE_LENGTH))
    collision(out, "sphere", (0, 0, PROBE_LENGTH + TIP_R), (0, 0, 0), TIP_R)
    out.append('  </link>')
    # The tool point: centre of the spherical tip.
    fixed_joint(out, "probe_tip_joint", "probe", "probe_tip", PROBE_LENGTH + TIP_R)
    out.append('  <link name="probe_tip">')
    inertial(out, 0, (0, 0, 0), (0, 0, 0), "massless frame")
    out.append('  </link>')
    out.append('</robot>')
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "iiwa14.urdf")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")

if __name__ == "__main__":
    main()
