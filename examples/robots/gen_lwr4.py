"""Writes lwr4.urdf next to this file: the KUKA LWR IV with a probe tool (spherical tip).

Run `python3 gen_lwr4.py`. Every number is stated here with where it comes from:
  kinematics, limits: KUKA LWR 4+ data (d = 0.11 + 0.2005, 0.20 + 0.20, 0.20 + 0.19, 0.078 m;
    A1/E1/A4/A6 +-170 deg, A2/A3/A5 +-120 deg), as collected from CentroEPiaggio/kuka-lwr (Unlicense);
  inertials: geometric approximations (solid boxes/cylinders with the masses of the same model,
    with its swapped iyy/izz corrected), NOT identified values;
  collisions: primitive spheres/cylinders of the same model;
  probe: a made-up aluminium probe (0.2 kg shaft + adapter, 10 mm radius spherical tip, 0.11 m
    from the flange face), the tool the skills touch with.
The flange frame equals standard-DH frame 7 of the LWR IV (tested in runtime/tests/robot_model.rs).
"""
import math, os

def rad(deg):
    return deg * math.pi / 180.0

def solid_box(m, x, y, z):
    return (m * (y * y + z * z) / 12, m * (x * x + z * z) / 12, m * (x * x + y * y) / 12)

def solid_cylinder_z(m, r, h):
    side = m * (3 * r * r + h * h) / 12
    return (side, side, m * r * r / 2)

def num(x):
    s = "%.12g" % x
    return "0" if s in ("0", "-0") else s

def vec(t):
    return " ".join(num(x) for x in t)

# Moving links: (link, mass kg, centre of mass in link frame, principal inertia, what it is).
LINKS = [
    ("lwr_base_link", 2.0, (0, 0, 0.055), solid_cylinder_z(2.0, 0.06, 0.11), "cylinder r 0.06 h 0.11"),
    ("lwr_1_link", 2.35, (0, -0.06, 0.13), solid_box(2.35, 0.06, 0.12, 0.26), "box 0.06 x 0.12 x 0.26"),
    ("lwr_2_link", 2.35, (0, 0.06, 0.07), solid_box(2.35, 0.06, 0.12, 0.26), "box 0.06 x 0.12 x 0.26"),
    ("lwr_3_link", 2.35, (0, 0.06, 0.13), solid_box(2.35, 0.06, 0.12, 0.26), "box 0.06 x 0.12 x 0.26"),
    ("lwr_4_link", 2.35, (0, -0.06, 0.07), solid_box(2.35, 0.06, 0.12, 0.26), "box 0.06 x 0.12 x 0.26"),
    ("lwr_5_link", 2.35, (0, 0, 0.124), solid_box(2.35, 0.06, 0.12, 0.248), "box 0.06 x 0.12 x 0.248"),
    ("lwr_6_link", 1.1, (0, 0, 0.0625), solid_box(1.1, 0.125, 0.125, 0.125), "cube 0.125"),
    ("lwr_7_link", 0.25, (0, 0, 0), solid_box(0.25, 0.1, 0.1, 0.1), "cube 0.1"),
]
# Revolute joints: (name, parent, child, z offset m, axis, limit deg, effort N m, velocity deg/s).
JOINTS = [
    ("lwr_a1_joint", "lwr_base_link", "lwr_1_link", 0.11, (0, 0, 1), 170, 176, 110),
    ("lwr_a2_joint", "lwr_1_link", "lwr_2_link", 0.2005, (0, -1, 0), 120, 176, 110),
    ("lwr_e1_joint", "lwr_2_link", "lwr_3_link", 0.20, (0, 0, 1), 170, 100, 128),
    ("lwr_a3_joint", "lwr_3_link", "lwr_4_link", 0.20, (0, 1, 0), 120, 100, 128),
    ("lwr_a4_joint", "lwr_4_link", "lwr_5_link", 0.20, (0, 0, 1), 170, 100, 204),
    ("lwr_a5_joint", "lwr_5_link", "lwr_6_link", 0.19, (0, -1, 0), 120, 38, 184),
    ("lwr_a6_joint", "lwr_6_link", "lwr_7_link", 0.078, (0, 0, 1), 170, 38, 184),
]
# Collision primitives per link: ("sphere", xyz, rpy, radius) or ("cylinder", xyz, rpy, (radius, length)).
COLLISIONS = {
    "lwr_base_link": [("cylinder", (0, 0, 0.055), (0, 0, 0), (0.07, 0.11))],
    "lwr_1_link": [("sphere", (0, 0, 0), (0, 0, 0), 0.07), ("sphere", (0, 0.06, 0.2), (0, 0, 0), 0.07),
                   ("cylinder", (0, 0.03, 0.1), (-0.291, 0, 0), (0.07, 0.208))],
    "lwr_2_link": [("sphere", (0, 0, 0.2), (0, 0, 0), 0.07), ("sphere", (0, -0.06, 0), (0, 0, 0), 0.07),
                   ("cylinder", (0, -0.03, 0.1), (-0.291, 0, 0), (0.07, 0.208))],
    "lwr_3_link": [("sphere", (0, 0, 0), (0, 0, 0), 0.07), ("sphere", (0, -0.06, 0.2), (0, 0, 0), 0.07),
                   ("cylinder", (0, -0.03, 0.1), (0.291, 0, 0), (0.07, 0.208))],
    "lwr_4_link": [("sphere", (0, 0, 0.2), (0, 0, 0), 0.07), ("sphere", (0, 0.06, 0), (0, 0, 0), 0.07),
                   ("cylinder", (0, 0.03, 0.1), (0.291, 0, 0), (0.07, 0.208))],
    "lwr_5_link": [("sphere", (0, 0, 0), (0, 0, 0), 0.07), ("sphere", (0, 0.04, 0.19), (0, 0, 0), 0.07),
                   ("cylinder", (0, 0.02, 0.095), (-0.207, 0, 0), (0.07, 0.198))],
    "lwr_6_link": [("sphere", (0, -0.01, 0), (0, 0, 0), 0.08)],
    "lwr_7_link": [("cylinder", (0, 0, 0), (0, 0, 0), (0.04, 0.05))],
}
PROBE_MASS, PROBE_LENGTH, PROBE_SHAFT_R, TIP_R = 0.2, 0.1, 0.008, 0.01

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
           '<!-- KUKA LWR IV (LWR 4+) with a probe tool. Written by gen_lwr4.py: see it for every number\'s source.',
           '     Kinematics are the LWR IV\'s; inertials are geometric approximations, not identified values. -->',
           '<robot name="kuka_lwr4">',
           '  <link name="world"/>']
    fixed_joint(out, "world_to_base", "world", "lwr_base_link", 0)
    by_child = {j[2]: j for j in JOINTS}
    for (link, m, com, inertia, what) in LINKS:
        if link in by_child:
            (name, parent, child, z, axis, lim, effort, vel) = by_child[link]
            out.append('  <joint name="%s" type="revolute">' % name)
            out.append('    <origin xyz="0 0 %s" rpy="0 0 0"/>' % num(z))
            out.append('    <parent link="%s"/>' % parent)
            out.append('    <child link="%s"/>' % child)
            out.append('    <axis xyz="%s"/>' % vec(axis))
            out.append('    <limit lower="%s" upper="%s" effort="%s" velocity="%s"/>'
                       % (num(-rad(lim)), num(rad(lim)), num(effort), num(rad(vel))))
            out.append('  </joint>')
        out.append('  <link name="%s">' % link)
        inertial(out, m, com, inertia, what)
        for c in COLLISIONS[link]:
            collision(out, *c)
        out.append('  </link>')
    # The flange: DH frame 7, where the wrist force/torque sensor sits. Massless frame.
    fixed_joint(out, "lwr_flange_joint", "lwr_7_link", "lwr_flange", 0)
    out.append('  <link name="lwr_flange">')
    inertial(out, 0, (0, 0, 0), (0, 0, 0), "massless frame")
    out.append('  </link>')
    # The probe: a shaft along the flange z axis ending in a spherical tip.
    fixed_joint(out, "probe_joint", "lwr_flange", "probe", 0)
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
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "lwr4.urdf")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")

if __name__ == "__main__":
    main()
