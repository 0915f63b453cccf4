#!/usr/bin/env python3
"""make_gltf.py — writes the glTF 2.0 test inputs of tests/data/gltf/.

Run from the repository root after make_binary_parts.c (README.md here).
Standard library only: JSON, struct, zlib (PNG). Every file is small and
deterministic; rerunning rewrites the same bytes.
"""
import base64
import json
import math
import os
import struct
import zlib

OUT = os.path.join("tests", "data", "gltf")

# 4 x 4 RGB texels, top row first: red/green over blue/yellow quadrants
TEXELS = [
    [(200, 40, 40)] * 2 + [(40, 200, 40)] * 2,
    [(200, 40, 40)] * 2 + [(40, 200, 40)] * 2,
    [(40, 40, 200)] * 2 + [(220, 220, 40)] * 2,
    [(40, 40, 200)] * 2 + [(220, 220, 40)] * 2,
]


def png_bytes(texels):
    h, w = len(texels), len(texels[0])
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in texels)

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def textured_box():
    """24 vertices (4 per face, split for normals and uvs), 36 indices, CCW from outside."""
    faces = [  # (normal axis, sign, u axis, v axis)
        (0, 1, 1, 2), (0, -1, 2, 1), (1, 1, 2, 0), (1, -1, 0, 2), (2, 1, 0, 1), (2, -1, 1, 0),
    ]
    pos, nrm, uv, idx = [], [], [], []
    for axis, sign, ua, va in faces:
        base = len(pos)
        for (a, b) in ((0, 0), (1, 0), (1, 1), (0, 1)):
            p = [0.0, 0.0, 0.0]
            p[axis] = 0.5 * sign
            p[ua] = a - 0.5
            p[va] = b - 0.5
            n = [0.0, 0.0, 0.0]
            n[axis] = float(sign)
            pos.append(p)
            nrm.append(n)
            uv.append([float(a), float(1 - b)])  # glTF: v runs down
        # CCW seen from outside: u x v must point along the normal
        cross = [0.0, 0.0, 0.0]
        cross[3 - ua - va] = 1.0 if (ua + 1) % 3 == va else -1.0
        if cross[axis] * sign > 0:
            idx += [base, base + 1, base + 2, base, base + 2, base + 3]
        else:
            idx += [base, base + 2, base + 1, base, base + 3, base + 2]
    return pos, nrm, uv, idx


class Doc:
    """A glTF document with one growing buffer."""

    def __init__(self):
        self.bin = bytearray()
        self.g = {"asset": {"version": "2.0", "generator": "meso tests/data/gltf/make_gltf.py"},
                  "buffers": [], "bufferViews": [], "accessors": [], "meshes": [], "nodes": [],
                  "scenes": [{"nodes": []}], "scene": 0}

    def view(self, data, target=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            v["target"] = target
        self.bin += data
        self.g["bufferViews"].append(v)
        return len(self.g["bufferViews"]) - 1

    def floats(self, rows, typ):
        flat = [x for r in rows for x in r]
        v = self.view(struct.pack("<%df" % len(flat), *flat), 34962)
        acc = {"bufferView": v, "componentType": 5126, "count": len(rows), "type": typ}
        if typ == "VEC3":
            acc["min"] = [min(r[k] for r in rows) for k in range(3)]
            acc["max"] = [max(r[k] for r in rows) for k in range(3)]
        self.g["accessors"].append(acc)
        return len(self.g["accessors"]) - 1

    def indices(self, idx, ctype=5123):
        fmt = {5121: "B", 5123: "H", 5125: "I"}[ctype]
        v = self.view(struct.pack("<%d%s" % (len(idx), fmt), *idx), 34963)
        self.g["accessors"].append({"bufferView": v, "componentType": ctype, "count": len(idx), "type": "SCALAR"})
        return len(self.g["accessors"]) - 1

    def box_mesh(self, material=None, name="box"):
        pos, nrm, uv, idx = textured_box()
        prim = {"attributes": {"POSITION": self.floats(pos, "VEC3"), "NORMAL": self.floats(nrm, "VEC3"),
                               "TEXCOORD_0": self.floats(uv, "VEC2")},
                "indices": self.indices(idx), "mode": 4}
        if material is not None:
            prim["material"] = material
        self.g["meshes"].append({"name": name, "primitives": [prim]})
        return len(self.g["meshes"]) - 1

    def texture(self, image_bytes, mime, factor=(1.0, 1.0, 1.0, 1.0), embed_view=False):
        g = self.g
        if embed_view:
            img = {"bufferView": self.view(image_bytes), "mimeType": mime}
        else:
            img = {"uri": "data:%s;base64,%s" % (mime, base64.b64encode(image_bytes).decode())}
        g.setdefault("images", []).append(img)
        g.setdefault("samplers", []).append({"magFilter": 9728, "minFilter": 9728})
        g.setdefault("textures", []).append({"source": len(g["images"]) - 1, "sampler": len(g["samplers"]) - 1})
        g.setdefault("materials", []).append({"pbrMetallicRoughness": {
            "baseColorFactor": list(factor), "baseColorTexture": {"index": len(g["textures"]) - 1},
            "metallicFactor": 0.0}})
        return len(g["materials"]) - 1

    def node(self, **kw):
        self.g["nodes"].append(kw)
        return len(self.g["nodes"]) - 1

    def finish_uri(self, uri):
        self.g["buffers"] = [{"byteLength": len(self.bin), "uri": uri}]
        return self.g

    def write_gltf(self, name, bin_name=None):
        if bin_name:
            with open(os.path.join(OUT, bin_name), "wb") as f:
                f.write(self.bin)
            self.finish_uri(bin_name)
        else:
            self.finish_uri("data:application/octet-stream;base64," + base64.b64encode(bytes(self.bin)).decode())
        with open(os.path.join(OUT, name), "w") as f:
            json.dump(self.g, f, indent=1)
            f.write("\n")

    def write_glb(self, name):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.g["buffers"] = [{"byteLength": len(self.bin)}]
        js = json.dumps(self.g).encode()
        js += b" " * ((4 - len(js) % 4) % 4)
        total = 12 + 8 + len(js) + 8 + len(self.bin)
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(struct.pack("<4sII", b"glTF", 2, total))
            f.write(struct.pack("<I4s", len(js), b"JSON") + js)
            f.write(struct.pack("<I4s", len(self.bin), b"BIN\x00") + bytes(self.bin))


def box_doc(material=True):
    d = Doc()
    mat = d.texture(png_bytes(TEXELS), "image/png", factor=(1.0, 0.8, 0.6, 1.0)) if material else None
    d.node(name="box", mesh=d.box_mesh(mat))
    d.g["scenes"][0]["nodes"] = [0]
    return d


def main():
    # textured box: external .bin, PNG texture (data URI)
    box_doc().write_gltf("box.gltf", "box.bin")
    # the same with the buffer embedded as a data: URI
    box_doc().write_gltf("box_embedded.gltf")
    # .glb with a JPEG base-colour texture stored in the BIN chunk
    d = Doc()
    with open(os.path.join(OUT, "texture.jpg"), "rb") as f:
        mat = d.texture(f.read(), "image/jpeg", embed_view=True)
    d.node(name="box", mesh=d.box_mesh(mat))
    d.g["scenes"][0]["nodes"] = [0]
    d.write_glb("box.glb")

    # multi-node scene: root (translation) with three boxes: a matrix (scale 2,
    # moved up), TRS (90 deg about z, moved down), a mirror (scale x -1:
    # winding reversed); a fourth box on a node outside the scene
    d = Doc()
    mesh = d.box_mesh(None)
    s, c = math.sin(math.pi / 4), math.cos(math.pi / 4)
    d.node(name="root", translation=[10.0, 0.0, 0.0], children=[1, 2, 3])
    d.node(name="A", mesh=mesh, matrix=[2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 5, 0, 1])
    d.node(name="B", mesh=mesh, rotation=[0.0, 0.0, s, c], translation=[0.0, -5.0, 0.0])
    d.node(name="C", mesh=mesh, scale=[-1.0, 1.0, 1.0], translation=[0.0, 0.0, 5.0])
    d.node(name="outside", mesh=mesh, translation=[0.0, 0.0, -20.0])
    d.g["scenes"][0]["nodes"] = [0]
    d.write_gltf("scene.gltf", "scene.bin")

    # a KHR_draco_mesh_compression primitive (box_draco.drc, make_binary_parts.c)
    d = Doc()
    with open(os.path.join(OUT, "box_draco.drc"), "rb") as f:
        drc = f.read()
    dv = d.view(drc)
    d.g["accessors"] += [
        {"componentType": 5126, "count": 8, "type": "VEC3", "min": [-0.5] * 3, "max": [0.5] * 3},
        {"componentType": 5126, "count": 8, "type": "VEC2"},
    ]
    # no "indices" accessor: tinygltf (built without Draco) refuses one without a bufferView
    d.g["meshes"].append({"name": "draco_box", "primitives": [{
        "attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "mode": 4,
        "extensions": {"KHR_draco_mesh_compression": {"bufferView": dv, "attributes": {"POSITION": 0,
                                                                                       "TEXCOORD_0": 1}}}}]})
    d.node(name="draco", mesh=0)
    d.g["scenes"][0]["nodes"] = [0]
    d.g["extensionsUsed"] = ["KHR_draco_mesh_compression"]
    d.g["extensionsRequired"] = ["KHR_draco_mesh_compression"]
    d.write_glb("box_draco.glb")

    # tests/data/sphere.obj as glTF: the same vertices in the same order, the
    # same triangles (the OBJ's faces are triangles)
    d = Doc()
    pos, tri = [], []
    with open(os.path.join("tests", "data", "sphere.obj")) as f:
        for line in f:
            w = line.split()
            if w and w[0] == "v":
                pos.append([float(x) for x in w[1:4]])
            elif w and w[0] == "f":
                tri += [int(x.split("/")[0]) - 1 for x in w[1:4]]
    d.g["meshes"].append({"name": "sphere", "primitives": [{
        "attributes": {"POSITION": d.floats(pos, "VEC3")}, "indices": d.indices(tri, 5125)}]})
    d.node(name="sphere", mesh=0)
    d.g["scenes"][0]["nodes"] = [0]
    d.write_glb("sphere.glb")

    bad_cases()


def cube8(doc, positions=None, idx=None, ptype="VEC3", ictype=5123):
    """An 8-vertex box (welded already) for the malformed cases."""
    pos = positions or [[x, y, z] for z in (-0.5, 0.5) for y in (-0.5, 0.5) for x in (-0.5, 0.5)]
    tri = idx or [0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2,
                  1, 3, 7, 1, 7, 5]
    flat = [v for p in pos for v in p]
    pv = doc.view(struct.pack("<%df" % len(flat), *flat))
    doc.g["accessors"].append({"bufferView": pv, "componentType": 5126, "count": len(pos), "type": ptype})
    iv = doc.view(struct.pack("<%dH" % len(tri), *tri))
    doc.g["accessors"].append({"bufferView": iv, "componentType": ictype, "count": len(tri), "type": "SCALAR"})
    doc.g["meshes"].append({"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]})
    doc.node(name="cube", mesh=0)
    doc.g["scenes"][0]["nodes"] = [0]
    return doc


def bad(name, edit=None, **kw):
    d = cube8(Doc(), **kw)
    d.finish_uri("data:application/octet-stream;base64," + base64.b64encode(bytes(d.bin)).decode())
    if edit:
        edit(d.g)
    with open(os.path.join(OUT, name), "w") as f:
        json.dump(d.g, f, indent=1)
        f.write("\n")


def bad_cases():
    """Each file breaks one rule; tests/integration/test_gltf.c lists the code each gets."""
    bad("cube8.gltf")  # the valid base of the cases below
    bad("bad_index.gltf", idx=[0, 2, 3, 0, 3, 9] + [0, 1, 2] * 10)
    bad("bad_missing_buffer.gltf", lambda g: g["buffers"][0].update(uri="missing.bin"))
    bad("bad_position_type.gltf", lambda g: g["accessors"][0].update(type="VEC2"))
    bad("bad_index_type.gltf", lambda g: g["accessors"][1].update(componentType=5126))
    bad("bad_accessor_bounds.gltf", lambda g: g["accessors"][0].update(count=9))
    bad("bad_view_bounds.gltf", lambda g: g["bufferViews"][1].update(byteOffset=4096))
    # 150 million zero positions (no bufferView) claimed by a 1.6 KB file
    bad("bad_zeros_count.gltf", lambda g: (g["accessors"][0].pop("bufferView"), g["accessors"][0].update(count=150000000)))
    bad("bad_nan.gltf", positions=[[float("nan"), 0.0, 0.0]] + [[x, y, z] for z in (-0.5, 0.5) for y in (-0.5, 0.5)
                                                                 for x in (-0.5, 0.5)][1:])
    bad("bad_cycle.gltf", lambda g: g["nodes"].extend([{"children": [2]}, {"children": [1]}]))
    bad("bad_two_parents.gltf", lambda g: g["nodes"].extend([{"children": [0]}, {"children": [0]}]) or
        g["scenes"][0].update(nodes=[1, 2]))
    bad("bad_schema.gltf", lambda g: g["accessors"][0].pop("componentType"))
    bad("bad_lines.gltf", lambda g: g["meshes"][0]["primitives"][0].update(mode=1))
    bad("bad_sparse.gltf", lambda g: g["accessors"][0].update(sparse={
        "count": 1, "indices": {"bufferView": 1, "componentType": 5123},
        "values": {"bufferView": 0}}))
    bad("bad_extension.gltf", lambda g: g.update(extensionsUsed=["EXT_meshopt_compression"],
                                                 extensionsRequired=["EXT_meshopt_compression"]))
    bad("bad_reference.gltf", lambda g: g["nodes"][0].update(mesh=7))
    bad("bad_texture.gltf", lambda g: (
        g.update(images=[{"uri": "data:image/png;base64," + base64.b64encode(b"not a png at all").decode()}],
                 textures=[{"source": 0}],
                 materials=[{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]),
        g["meshes"][0]["primitives"][0].update(material=0)))
    bad("bad_empty.gltf", lambda g: g["nodes"][0].pop("mesh"))
    with open(os.path.join(OUT, "bad_not_json.gltf"), "w") as f:
        f.write("{ \"asset\": { \"version\": \"2.0\" }, \"meshes\": [ \n")
    big_texture()


def big_texture():
    """box.gltf with its base-colour PNG replaced by a 4096 x 4096 1-bit one
    (2 KB): decoded it needs 16-64 MB, so --max-memory 32M must refuse it
    before decoding."""
    w = h = 4096
    raw = b"".join(b"\x00" + b"\x00" * ((w + 7) // 8) for _ in range(h))

    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 1, 0, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    with open(os.path.join(OUT, "box.gltf")) as f:
        g = json.load(f)
    g["images"][0]["uri"] = "data:image/png;base64," + base64.b64encode(png).decode()
    with open(os.path.join(OUT, "big_texture.gltf"), "w") as f:
        json.dump(g, f, indent=1)


if __name__ == "__main__":
    main()
