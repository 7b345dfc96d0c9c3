#!/usr/bin/python3
"""Write the benchmark mechanisms as URDF (tools/bench/models.hpp builds the same ones in C++):
chain_N.urdf and tree_N.urdf in the given folder, and quadruped_18.urdf.

chain: N links in series, revolute joints; joint 1 at the origin, every later joint at (0.3, 0, 0)
in its parent's frame; axes cycling z, y, x; every link mass 1, centre of mass (0.15, 0, 0),
inertia diag(0.01, 0.02, 0.03).  Binary tree: the same links, parent of link i is link (i-1)//2.
quadruped_18: a 12 kg trunk and four legs of three revolute joints (hip abduction about x, hip and
knee flexion about y), the mass properties of a small quadruped; load it with free_root=True for
the 18-DOF free-floating robot (6 + 12) of tools/bench/batch.py.
"""
import argparse
import os

AXES = ["0 0 1", "0 1 0", "1 0 0"]


def urdf(n, binary):
    out = [f'<?xml version="1.0"?>', f'<robot name="{"tree" if binary else "chain"}_{n}">',
           '  <mujoco><compiler discardvisual="true" balanceinertia="false" fusestatic="false"/></mujoco>',
           '  <link name="world"/>']
    for i in range(n):
        out.append(f'  <link name="link{i + 1}"><inertial><origin xyz="0.15 0 0"/><mass value="1"/>'
                   f'<inertia ixx="0.01" iyy="0.02" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>')
    for i in range(n):
        parent = "world" if i == 0 else f"link{((i - 1) // 2 if binary else i - 1) + 1}"
        xyz = "0 0 0" if i == 0 else "0.3 0 0"
        out.append(f'  <joint name="joint{i + 1}" type="continuous"><parent link="{parent}"/>'
                   f'<child link="link{i + 1}"/><origin xyz="{xyz}"/><axis xyz="{AXES[i % 3]}"/></joint>')
    out.append("</robot>")
    return "\n".join(out) + "\n"


def quadruped():
    def inertial(mass, xyz, ixx, iyy, izz):
        return (f'<inertial><origin xyz="{xyz}"/><mass value="{mass}"/>'
                f'<inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/></inertial>')
    out = ['<?xml version="1.0"?>', '<robot name="quadruped_18">',
           f'  <link name="trunk">{inertial(12.0, "0.01 0 0", 0.07, 0.26, 0.28)}</link>']
    for leg, (x, y) in {"fl": (0.19, 0.05), "fr": (0.19, -0.05), "hl": (-0.19, 0.05), "hr": (-0.19, -0.05)}.items():
        side = 1 if y > 0 else -1
        links = [(f"{leg}_hip", inertial(0.7, f"0 {0.01 * side} 0", 0.0005, 0.0008, 0.0006), "trunk", f"{x} {y} 0", "1 0 0"),
                 (f"{leg}_thigh", inertial(1.0, f"0 {-0.02 * side} -0.03", 0.006, 0.006, 0.001), f"{leg}_hip",
                  f"0 {0.08 * side} 0", "0 1 0"),
                 (f"{leg}_calf", inertial(0.2, "0 0 -0.1", 0.003, 0.003, 0.00005), f"{leg}_thigh", "0 0 -0.21", "0 1 0")]
        for name, inert, parent, xyz, axis in links:
            out.append(f'  <link name="{name}">{inert}</link>')
            out.append(f'  <joint name="{name}_joint" type="continuous"><parent link="{parent}"/><child link="{name}"/>'
                       f'<origin xyz="{xyz}"/><axis xyz="{axis}"/></joint>')
    out.append("</robot>")
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder", nargs="?", default="build/bench_models", help="where to write (default: %(default)s)")
    folder = ap.parse_args().folder
    os.makedirs(folder, exist_ok=True)
    for n in [1, 2, 4, 8, 16, 32, 64, 128, 256]:
        with open(os.path.join(folder, f"chain_{n}.urdf"), "w") as f:
            f.write(urdf(n, False))
    for n in [1, 3, 7, 15, 31, 63, 127, 255]:
        with open(os.path.join(folder, f"tree_{n}.urdf"), "w") as f:
            f.write(urdf(n, True))
    with open(os.path.join(folder, "quadruped_18.urdf"), "w") as f:
        f.write(quadruped())
    print(f"wrote the benchmark URDFs to {folder}")


if __name__ == "__main__":
    main()
