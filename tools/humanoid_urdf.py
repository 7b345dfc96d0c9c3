#!/usr/bin/python3
"""Writes a humanoid-like URDF as real descriptions are written, and times `soadyn inspect` on it.

50 DOF (waist 3, neck 2, legs 2 x 6, arms 2 x 7, hands 2 x 9, a spinning lidar), a massless root
frame welded to the pelvis, 100 fixed joints (sensor and optical frames, point-mass sensors, rods,
fingertip and mocap frames), mimic tags on the distal finger joints, package:// meshes on every
link, transmissions and Gazebo blocks.  The numbers are seeded, so the file is the same each run.

    tools/humanoid_urdf.py -o humanoid.urdf                    # write it
    tools/humanoid_urdf.py -o humanoid.urdf --time build/soadyn  # and time inspect (process start included)
"""
import argparse
import math
import random
import resource
import statistics
import subprocess
import sys
import time

DOF = 50
FIXED = 100


class Robot:
    def __init__(self, seed):
        self.rng = random.Random(seed)
        self.links, self.joints, self.extras = [], [], []
        self.dof = self.fixed = 0

    def inertial(self, mass, size, kind="box"):
        """<inertial> of a box (a, b, c), a rod of length size[0] along x, or a point mass."""
        r = self.rng
        com = " ".join(f"{r.uniform(-0.3, 0.3) * s:.4f}" for s in size)
        if kind == "point":
            ixx = iyy = izz = 0.0
        elif kind == "rod":
            ixx, iyy = 0.0, mass * size[0] ** 2 / 12
            izz = iyy
        else:
            a, b, c = size
            ixx, iyy, izz = (mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12, mass * (a * a + b * b) / 12)
        rpy = f"{r.uniform(-0.2, 0.2):.3f} {r.uniform(-0.2, 0.2):.3f} 0" if kind == "box" else "0 0 0"
        return (f'    <inertial>\n      <origin xyz="{com}" rpy="{rpy}"/>\n      <mass value="{mass:.4f}"/>\n'
                f'      <inertia ixx="{ixx:.6g}" iyy="{iyy:.6g}" izz="{izz:.6g}" ixy="0" ixz="0" iyz="0"/>\n'
                f'    </inertial>\n')

    def link(self, name, mass=None, size=(0.1, 0.1, 0.1), kind="box", mesh=True):
        body = self.inertial(mass, size, kind) if mass else ""
        if mesh:
            body += (f'    <visual>\n      <origin xyz="0 0 0" rpy="0 0 0"/>\n      <geometry>\n'
                     f'        <mesh filename="package://humanoid_description/meshes/{name}.dae"/>\n'
                     f'      </geometry>\n      <material name="grey"/>\n    </visual>\n'
                     f'    <collision>\n      <geometry>\n'
                     f'        <mesh filename="package://humanoid_description/meshes/collision/{name}.stl"/>\n'
                     f'      </geometry>\n    </collision>\n')
        self.links.append(f'  <link name="{name}">\n{body}  </link>\n' if body else f'  <link name="{name}"/>\n')

    def joint(self, name, kind, parent, child, xyz, axis="0 0 1", rpy="0 0 0", mimic=None):
        text = (f'  <joint name="{name}" type="{kind}">\n    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
                f'    <origin xyz="{xyz}" rpy="{rpy}"/>\n')
        if kind != "fixed":
            text += f'    <axis xyz="{axis}"/>\n'
            if kind != "continuous":
                text += '    <limit lower="-2.5" upper="2.5" effort="150" velocity="6"/>\n'
            text += '    <dynamics damping="0.1" friction="0.05"/>\n'
            if mimic:
                text += f'    <mimic joint="{mimic}" multiplier="1.0" offset="0"/>\n'
            self.dof += 1
            self.extras.append(
                f'  <transmission name="{name}_trans">\n    <type>transmission_interface/SimpleTransmission</type>\n'
                f'    <joint name="{name}">\n      <hardwareInterface>hardware_interface/EffortJointInterface'
                f'</hardwareInterface>\n    </joint>\n    <actuator name="{name}_motor">\n'
                f'      <mechanicalReduction>100</mechanicalReduction>\n    </actuator>\n  </transmission>\n')
        else:
            self.fixed += 1
        self.joints.append(text + '  </joint>\n')

    def moving(self, name, parent, child, xyz, axis, mass, size, **kw):
        self.link(child, mass, size)
        self.joint(name, kw.pop("kind", "revolute"), parent, child, xyz, axis, **kw)

    def weld(self, parent, child, xyz, mass=None, kind="box", size=(0.02, 0.02, 0.02), rpy="0 0 0"):
        self.link(child, mass, size, kind, mesh=mass is not None)
        self.joint(f"{child}_joint", "fixed", parent, child, xyz, rpy=rpy)


def camera(rb, parent, name, xyz):
    rb.weld(parent, f"{name}_link", xyz, 0.05, "point")
    rb.weld(f"{name}_link", f"{name}_optical_frame", "0 0 0", rpy=f"{-math.pi / 2} 0 {-math.pi / 2}")
    rb.weld(f"{name}_link", f"{name}_depth_frame", "0 0.02 0")


def hand(rb, side, s):
    h = f"{side}_hand"
    for f, y in (("thumb", 0.03), ("index", 0.01), ("middle", -0.01)):
        parent = h
        for k, seg in enumerate(("proximal", "middle", "distal")):
            child = f"{side}_{f}_{seg}"
            mimic = f"{side}_{f}_middle_joint" if seg == "distal" else None
            rb.moving(f"{child}_joint", parent, child, f"{0.08 if k == 0 else 0.035} {s * y if k == 0 else 0} 0",
                      "0 1 0", 0.02, (0.035, 0.015, 0.015), mimic=mimic)
            parent = child
        rb.weld(parent, f"{side}_{f}_tip", "0.03 0 0")
        rb.weld(parent, f"{side}_{f}_pad", "0.02 0 -0.008", 0.002, "point")


def limb(rb, chain, parent, xyz0):
    for k, (name, axis, mass, size) in enumerate(chain):
        rb.moving(f"{name}_joint", parent, name, xyz0 if k == 0 else f"0 0 {-size[2]:.3f}", axis, mass, size)
        parent = name
    return parent


def build(seed=1):
    rb = Robot(seed)
    rb.link("base_link", mesh=False)  # the frame the pose is given in: no mass of its own
    rb.weld("base_link", "pelvis", "0 0 0", 8.0, size=(0.25, 0.3, 0.15))
    rb.weld("pelvis", "imu_link", "0 0 0.05")
    rb.weld("imu_link", "imu_frame", "0 0 0", 0.01, "point")
    parent = "pelvis"
    for name, axis in (("waist_yaw", "0 0 1"), ("waist_roll", "1 0 0"), ("waist_pitch", "0 1 0")):
        rb.moving(f"{name}_joint", parent, name, "0 0 0.08", axis, 1.0, (0.08, 0.08, 0.08))
        parent = name
    rb.weld(parent, "torso", "0 0 0.05", 15.0, size=(0.3, 0.35, 0.4))
    rb.weld("torso", "battery", "-0.1 0 0.1", 3.0, size=(0.1, 0.25, 0.15))
    rb.weld("torso", "chest_rod", "0 0 0.3", 0.4, "rod", size=(0.3, 0.02, 0.02))
    rb.moving("neck_yaw_joint", "torso", "neck", "0 0 0.45", "0 0 1", 0.5, (0.05, 0.05, 0.08))
    rb.moving("neck_pitch_joint", "neck", "head", "0 0 0.08", "0 1 0", 3.0, (0.2, 0.18, 0.22))
    for cam, y in (("left_eye", 0.04), ("right_eye", -0.04)):
        camera(rb, "head", cam, f"0.1 {y} 0.05")
    rb.weld("head", "lidar_mount", "0 0 0.15", 0.1, size=(0.05, 0.05, 0.03))
    rb.moving("lidar_spin_joint", "lidar_mount", "lidar", "0 0 0.03", "0 0 1", 0.4, (0.08, 0.08, 0.06),
              kind="continuous")
    rb.weld("lidar", "lidar_frame", "0 0 0.03")
    for side, s in (("left", 1), ("right", -1)):
        leg = [(f"{side}_hip_yaw", "0 0 1", 1.2, (0.08, 0.08, 0.06)), (f"{side}_hip_roll", "1 0 0", 1.5, (0.1, 0.1, 0.08)),
               (f"{side}_thigh", "0 1 0", 5.0, (0.12, 0.12, 0.4)), (f"{side}_shin", "0 1 0", 3.0, (0.1, 0.1, 0.4)),
               (f"{side}_ankle", "0 1 0", 0.5, (0.06, 0.06, 0.05)), (f"{side}_foot", "1 0 0", 1.2, (0.22, 0.1, 0.05))]
        foot = limb(rb, leg, "pelvis", f"0 {s * 0.1} -0.1")
        rb.weld(foot, f"{side}_sole", "0 0 -0.05")
        rb.weld(foot, f"{side}_ft_sensor", "0 0 -0.02", 0.1, "point")
        for k, x in enumerate((0.11, -0.08)):
            rb.weld(foot, f"{side}_{('toe', 'heel')[k]}", f"{x} 0 -0.05")
        arm = [(f"{side}_shoulder_pitch", "0 1 0", 1.0, (0.08, 0.08, 0.08)),
               (f"{side}_shoulder_roll", "1 0 0", 1.0, (0.08, 0.08, 0.08)),
               (f"{side}_upper_arm", "0 0 1", 2.0, (0.08, 0.08, 0.28)), (f"{side}_elbow", "0 1 0", 1.2, (0.07, 0.07, 0.25)),
               (f"{side}_wrist_yaw", "0 0 1", 0.4, (0.05, 0.05, 0.05)), (f"{side}_wrist_pitch", "0 1 0", 0.3, (0.05, 0.05, 0.04)),
               (f"{side}_hand", "1 0 0", 0.5, (0.1, 0.08, 0.03))]
        h = limb(rb, arm, "torso", f"0 {s * 0.22} 0.35")
        rb.weld(h, f"{side}_palm", "0.05 0 0")
        rb.weld(h, f"{side}_wrist_ft", "0 0 0.01", 0.08, "point")
        camera(rb, h, f"{side}_hand_camera", "0.04 0 0.03")
        hand(rb, side, s)
    k = 0
    while rb.fixed < FIXED:  # motion-capture markers, massless, until there are FIXED fixed joints
        rb.weld(("torso", "head", "pelvis", "left_foot", "right_foot")[k % 5], f"marker_{k}", f"0.01 0.02 {0.01 * k:.2f}")
        k += 1
    assert rb.dof == DOF and rb.fixed == FIXED, (rb.dof, rb.fixed)
    return ('<?xml version="1.0"?>\n<!-- generated by tools/humanoid_urdf.py -->\n'
            '<robot name="humanoid" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
            '  <material name="grey">\n    <color rgba="0.6 0.6 0.6 1"/>\n  </material>\n' + "".join(rb.links) +
            "".join(rb.joints) + "".join(rb.extras) +
            '  <gazebo>\n    <plugin name="control" filename="libgazebo_ros_control.so"/>\n  </gazebo>\n</robot>\n')


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", default="humanoid.urdf")
    ap.add_argument("--time", metavar="SOADYN", help="time `SOADYN inspect OUTPUT --free-root --json`")
    ap.add_argument("--runs", type=int, default=30)
    a = ap.parse_args()
    with open(a.output, "w") as f:
        f.write(build())
    print(f"{a.output}: {DOF} DOF, {FIXED} fixed joints")
    if a.time:
        cmd = [a.time, "inspect", a.output, "--free-root", "--json"]
        subprocess.run(cmd, check=True, capture_output=True)  # warm the file cache
        wall, cpu = [], []
        for _ in range(a.runs):
            r0, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True)
            t1, r1 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
            wall.append(t1 - t0)
            cpu.append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
        print(f"soadyn inspect --free-root, process start included, over {a.runs} runs: "
              f"wall median {1e3 * statistics.median(wall):.1f} ms (min {1e3 * min(wall):.1f}), "
              f"CPU median {1e3 * statistics.median(cpu):.1f} ms (min {1e3 * min(cpu):.1f})")

if __name__ == "__main__":
    sys.exit(main())
