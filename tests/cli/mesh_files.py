"""Small mesh files written by the tests of `soadyn view` (nothing of a public robot's meshes is in
the repository): a box and a square pyramid as binary and ASCII STL, OBJ and Collada, and a sphere
of a chosen number of triangles (for the page size of a robot with realistic meshes)."""
import math
import struct


def box(sx=1.0, sy=1.0, sz=1.0):
    """the box [-sx/2, sx/2] x [-sy/2, sy/2] x [-sz/2, sz/2]: 8 vertices, 12 triangles, outward"""
    verts = [(((i & 1) - 0.5) * sx, ((i >> 1 & 1) - 0.5) * sy, ((i >> 2 & 1) - 0.5) * sz) for i in range(8)]
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    faces = []
    for a, b, c, d in quads:
        faces += [(a, b, c), (a, c, d)]
    return verts, faces


def pyramid(size=1.0):
    """a square pyramid: base size x size at z = -size/2, apex at z = +size/2"""
    h = size / 2
    verts = [(-h, -h, -h), (h, -h, -h), (h, h, -h), (-h, h, -h), (0.0, 0.0, h)]
    faces = [(0, 2, 1), (0, 3, 2), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)]
    return verts, faces


def sphere(radius, triangles):
    """a UV sphere of about `triangles` triangles (rings x 2 segments each)"""
    rings = max(2, int(round(math.sqrt(triangles / 4))))
    segments = max(3, triangles // (2 * rings))
    verts = []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segments):
            ph = 2 * math.pi * j / segments
            verts.append((radius * math.sin(th) * math.cos(ph), radius * math.sin(th) * math.sin(ph), radius * math.cos(th)))
    faces = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            c, d = a + segments, b + segments
            faces += [(a, c, b), (b, c, d)]
    return verts, faces


def scaled(mesh, s):
    verts, faces = mesh
    return [tuple(s * x for x in v) for v in verts], faces


def normal(a, b, c):
    u = [b[k] - a[k] for k in range(3)]
    w = [c[k] - a[k] for k in range(3)]
    n = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
    length = math.sqrt(sum(x * x for x in n)) or 1.0
    return tuple(x / length for x in n)


def stl_binary(mesh):
    verts, faces = mesh
    out = [b"soadyn test mesh".ljust(80, b"\0"), struct.pack("<I", len(faces))]
    for f in faces:
        a, b, c = (verts[i] for i in f)
        out.append(struct.pack("<12fH", *normal(a, b, c), *a, *b, *c, 0))
    return b"".join(out)


def stl_ascii(mesh, name="part"):
    verts, faces = mesh
    lines = [f"solid {name}"]
    for f in faces:
        a, b, c = (verts[i] for i in f)
        lines.append("  facet normal {:.6g} {:.6g} {:.6g}".format(*normal(a, b, c)))
        lines.append("    outer loop")
        lines += ["      vertex {:.6g} {:.6g} {:.6g}".format(*p) for p in (a, b, c)]
        lines += ["    endloop", "  endfacet"]
    lines.append(f"endsolid {name}")
    return ("\n".join(lines) + "\n").encode()


def obj(mesh):
    verts, faces = mesh
    lines = ["# soadyn test mesh", "o part"]
    lines += ["v {:.6g} {:.6g} {:.6g}".format(*v) for v in verts]
    lines += ["f {} {} {}".format(*(i + 1 for i in f)) for f in faces]
    return ("\n".join(lines) + "\n").encode()


def dae(mesh, rgb=None, up_axis="Z_UP"):
    """a Collada file with one triangle mesh; with rgb, a Phong material of that diffuse colour"""
    verts, faces = mesh
    positions = " ".join("{:.6g} {:.6g} {:.6g}".format(*v) for v in verts)
    indices = " ".join(" ".join(str(i) for i in f) for f in faces)
    material = ""
    bind = ""
    mat_attr = ""
    if rgb is not None:
        color = "{:.4g} {:.4g} {:.4g} 1".format(*rgb)
        material = (f'<library_effects><effect id="paint-effect"><profile_COMMON><technique sid="common"><phong>'
                    f'<diffuse><color sid="diffuse">{color}</color></diffuse></phong></technique></profile_COMMON>'
                    f'</effect></library_effects><library_materials><material id="paint" name="paint">'
                    f'<instance_effect url="#paint-effect"/></material></library_materials>')
        bind = ('<bind_material><technique_common><instance_material symbol="paint" target="#paint"/>'
                '</technique_common></bind_material>')
        mat_attr = ' material="paint"'
    text = f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>{up_axis}</up_axis></asset>
  {material}
  <library_geometries><geometry id="part-mesh" name="part"><mesh>
    <source id="part-positions"><float_array id="part-positions-array" count="{3 * len(verts)}">{positions}</float_array>
      <technique_common><accessor source="#part-positions-array" count="{len(verts)}" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="part-vertices"><input semantic="POSITION" source="#part-positions"/></vertices>
    <triangles{mat_attr} count="{len(faces)}"><input semantic="VERTEX" source="#part-vertices" offset="0"/><p>{indices}</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene" name="scene">
    <node id="part" name="part" type="NODE"><instance_geometry url="#part-mesh" name="part">{bind}</instance_geometry></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""
    return text.encode()
