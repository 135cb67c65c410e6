#!/usr/bin/env python3
"""Writes the hand-made seed inputs of the fuzz targets (small valid files, one feature each).

Usage: python3 scripts/fuzz-seed.py OUT_DIR [MESH.ply.gz ...]   (writes OUT_DIR/<target>/<name>)

Each MESH (a binary little-endian PLY as written by `interreflect convert-mesh`) is also
re-encoded as ASCII PLY, OBJ (with normals when it has them) and GLB seeds.

Called by scripts/fuzz-seed.sh; the output is deterministic. The EXR seeds are not made here:
they are written by the crate's own `write_exr`/`write_exr_half` (see fuzz/seeds/exr/README).
"""
import base64
import gzip
import json
import os
import struct
import sys


def put(root, target, name, data):
    d = os.path.join(root, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


TETRA_P = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TETRA_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def ply_seeds(root):
    put(root, "ply", "ascii-tetra.ply",
        "ply\nformat ascii 1.0\ncomment tetrahedron\nelement vertex 4\n"
        "property float x\nproperty float y\nproperty float z\n"
        "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
        + "".join("%g %g %g\n" % p for p in TETRA_P)
        + "".join("3 %d %d %d\n" % f for f in TETRA_F))
    # ASCII with normals, a quad, an extra element and property, CRLF line ends.
    put(root, "ply", "ascii-normals-quad-crlf.ply",
        ("ply\nformat ascii 1.0\nobj_info x\nelement vertex 4\n"
         "property double x\nproperty double y\nproperty double z\n"
         "property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\n"
         "element face 1\nproperty list uchar uint vertex_indices\nproperty int flags\n"
         "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
         "0 0 0 0 0 1 255\n1 0 0 0 0 1 0\n1 1 0 0 0 1 7\n0 1 0 0 0 1 9\n"
         "4 0 1 2 3 5\n0 1\n").replace("\n", "\r\n"))
    for endian, fmt, tag in (("<", "binary_little_endian", "le"), (">", "binary_big_endian", "be")):
        head = ("ply\nformat %s 1.0\nelement vertex 4\n"
                "property float x\nproperty float y\nproperty float z\n"
                "property float nx\nproperty float ny\nproperty float nz\n"
                "element face 4\nproperty list uchar ushort vertex_indices\n"
                "element material 1\nproperty list uchar float weights\nend_header\n" % fmt)
        body = b""
        for p in TETRA_P:
            body += struct.pack(endian + "6f", *p, *p)
        for f in TETRA_F:
            body += struct.pack(endian + "B3H", 3, *f)
        body += struct.pack(endian + "B2f", 2, 0.5, 0.25)
        put(root, "ply", "binary-%s-tetra.ply" % tag, head.encode() + body)
    # int/double types, vertex_index, a polygon.
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex 5\n"
            "property double x\nproperty double y\nproperty double z\nproperty short s\n"
            "element face 1\nproperty list int int vertex_index\nend_header\n")
    body = b"".join(struct.pack("<3dh", x, y, 0.0, 1) for x, y in
                    ((0, 0), (1, 0), (1.5, 1), (0.5, 1.5), (-0.5, 1)))
    body += struct.pack("<6i", 5, 0, 1, 2, 3, 4)
    put(root, "ply", "binary-double-pentagon.ply", head.encode() + body)


def obj_seeds(root):
    put(root, "obj", "tetra.obj",
        "# tetrahedron\n" + "".join("v %g %g %g\n" % p for p in TETRA_P)
        + "".join("f %d %d %d\n" % tuple(i + 1 for i in f) for f in TETRA_F))
    put(root, "obj", "normals-uvs-negative.obj",
        "mtllib m.mtl\no quad\nv 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1 0\nvn 0 0 1\nvn 0 0.1 1\n"
        "usemtl red\ns 1\ng a b\nf -4/-4/-2 -3/-3/-2 -2/-2/-1 -1/-1/-1\n"
        "f 1//1 3//2 4//1\nl 1 2\np 3\n")
    put(root, "obj", "continuation-crlf.obj",
        "v 0 0 0\r\nv 1 0 \\\r\n 0\r\nv 0 1 0  # comment\r\nvt 0 0\r\nvt 1 0\r\nvt 0 1\r\nf 1/1 2/2 \\\r\n3/3\r\nf 1/1 3/3 2/2\r\n")


def gltf_doc(buffer, with_normals=True, nodes=None):
    pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    nrm = struct.pack("<9f", 0, 0, 1, 0, 0, 1, 0, 0, 1)
    idx = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    data = pos + nrm + idx
    attrs = {"POSITION": 0}
    if with_normals:
        attrs["NORMAL"] = 1
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [dict(buffer(data), byteLength=len(data))],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 36},
            {"buffer": 0, "byteOffset": 72, "byteLength": 6},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
        "meshes": [{"name": "tri", "primitives": [{"attributes": attrs, "indices": 2}]}],
        "nodes": nodes or [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    return doc, data


def data_uri(data):
    return {"uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}


def glb(doc, data):
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    data += b"\0" * (-len(data) % 4)
    chunks = struct.pack("<I4s", len(js), b"JSON") + js + struct.pack("<I4s", len(data), b"BIN\0") + data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def gltf_seeds(root):
    doc, data = gltf_doc(lambda d: data_uri(d))
    put(root, "gltf", "triangle-data-uri.gltf", json.dumps(doc, indent=1))
    # A hierarchy with TRS and matrix transforms (one mirroring), no normals.
    nodes = [
        {"children": [1, 2], "translation": [1, 2, 3], "rotation": [0, 0.7071068, 0, 0.7071068]},
        {"mesh": 0, "scale": [-1, 1, 1]},
        {"mesh": 0, "matrix": [2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 5, 0, 0, 1]},
    ]
    doc, data = gltf_doc(lambda d: data_uri(d), with_normals=False, nodes=nodes)
    put(root, "gltf", "hierarchy-data-uri.gltf", json.dumps(doc))
    doc, data = gltf_doc(lambda d: {})
    put(root, "gltf", "triangle.glb", glb(doc, data))


def hdr_seeds(root):
    def rgbe(r, g, b):
        m = max(r, g, b)
        if m < 1e-32:
            return bytes(4)
        import math
        e = math.floor(math.log2(m)) + 1
        s = 256.0 / 2.0 ** e
        return bytes([int(r * s), int(g * s), int(b * s), e + 128])
    px = [rgbe(0.5 + x, 1.0, 0.25 * y + 0.1) for y in range(2) for x in range(4)]
    put(root, "hdr", "flat-4x2.hdr",
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y 2 +X 4\n" + b"".join(px))
    # Old-style run (1,1,1,n) and the mirrored orientation.
    put(root, "hdr", "oldrun-flipped.hdr",
        b"#?RGBE\n\n+Y 2 -X 4\n" + px[0] + bytes([1, 1, 1, 3]) + px[1] + px[2] + px[3] + px[4])
    # New-style RLE, 8 wide, 2:1 lat-long proportions (8x4).
    line = bytes([2, 2, 0, 8])
    for c in (128, 64, 32, 129):
        line += bytes([128 + 4, c, 4, c, c + 1, c + 2, c + 3])
    put(root, "hdr", "rle-8x4.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n" + line * 4)


def scene_seeds(root):
    put(root, "scene_toml", "all-shapes.toml", """name = "shapes"
[camera]
position = [0, 1, 5]
look_at = [0, 0, 0]
up = [0, 1, 0]
fov_y = 40
width = 64
height = 48

[[lights]]
type = "point"
position = [0, 4, 0]
intensity = [10, 10, 10]

[materials.white]
model = "lambert"
diffuse = [0.8, 0.8, 0.8]

[[objects]]
material = "white"
shape = { type = "plane", size = [4, 4], subdivisions = 2 }

[[objects]]
material = "white"
shape = { type = "box", size = [1, 1, 1] }
transform = { translate = [0, 0.5, 0], rotate = [0, 30, 0], scale = 0.5 }

[[objects]]
material = "white"
shape = { type = "sphere", radius = 0.5, segments = 8 }
transform = { scale = [1, -1, 1] }

[[objects]]
material = "white"
shape = { type = "ring", radius = 1, height = 0.2, thickness = 0.05, segments = 12 }
""")


def clean_seeds(root):
    # flags, vertex count, positions (3 bytes each as small integers), triangles (3 bytes).
    tetra = bytes([0, 4]) + bytes(sum(TETRA_P, ())) + bytes(sum(TETRA_F, ()))
    put(root, "mesh_clean", "tetra", tetra)
    normals = bytes([0, 0, 1, 0, 0, 0, 255, 255, 255, 0, 0, 1])
    put(root, "mesh_clean", "tetra-normals", bytes([1, 4]) + bytes(sum(TETRA_P, ())) + normals
        + bytes(sum(TETRA_F, ())))
    # Duplicate (reversed) and degenerate triangles.
    put(root, "mesh_clean", "dup-degenerate", tetra + bytes([1, 2, 0, 0, 0, 1, 1, 1, 3]))
    # f32 coordinates.
    pos = b"".join(struct.pack("<3f", *p) for p in TETRA_P)
    put(root, "mesh_clean", "tetra-f32", bytes([2, 4]) + pos + bytes(sum(TETRA_F, ())))


def read_ply(path):
    """Reads the binary little-endian PLY that convert-mesh writes: positions, normals, faces."""
    data = gzip.open(path).read() if path.endswith(".gz") else open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode().split("\n")
    nv = nf = 0
    props = []
    index_fmt = "H"
    for line in head:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            nv = int(w[2])
        elif w[:2] == ["element", "face"]:
            nf = int(w[2])
        elif w[:1] == ["property"] and w[1] != "list":
            props.append(w[2])
        elif w[:2] == ["property", "list"]:
            index_fmt = {"ushort": "H", "uint": "I"}[w[3]]
    stride = 4 * len(props)
    pos, nrm, faces = [], [], []
    at = end
    for _ in range(nv):
        v = struct.unpack_from("<%df" % len(props), data, at)
        at += stride
        pos.append(v[:3])
        if len(props) >= 6:
            nrm.append(v[3:6])
    size = struct.calcsize("<" + index_fmt)
    for _ in range(nf):
        (n,) = struct.unpack_from("<B", data, at)
        faces.append(struct.unpack_from("<%d%s" % (n, index_fmt), data, at + 1))
        at += 1 + n * size
    return pos, nrm, faces


def mesh_seeds(root, path):
    name = os.path.basename(path).split(".")[0]
    pos, nrm, faces = read_ply(path)
    has_n = len(nrm) == len(pos)
    head = "ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n" % len(pos)
    if has_n:
        head += "property float nx\nproperty float ny\nproperty float nz\n"
    head += "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % len(faces)
    rows = ["%.6g %.6g %.6g" % p + (" %.4g %.4g %.4g" % nrm[i] if has_n else "") for i, p in enumerate(pos)]
    put(root, "ply", name + "-ascii.ply",
        head + "\n".join(rows) + "\n" + "".join("%d %s\n" % (len(f), " ".join(map(str, f))) for f in faces))
    obj = "".join("v %.6g %.6g %.6g\n" % p for p in pos)
    if has_n:
        obj += "".join("vn %.4g %.4g %.4g\n" % n for n in nrm)
        obj += "".join("f %s\n" % " ".join("%d//%d" % (i + 1, i + 1) for i in f) for f in faces)
    else:
        obj += "".join("f %s\n" % " ".join(str(i + 1) for i in f) for f in faces)
    put(root, "obj", name + ".obj", obj)
    tris = [(f[0], f[k], f[k + 1]) for f in faces for k in range(1, len(f) - 1)]
    pdata = b"".join(struct.pack("<3f", *p) for p in pos)
    idata = b"".join(struct.pack("<3I", *t) for t in tris)
    data = pdata + idata
    lo = [min(p[k] for p in pos) for k in range(3)]
    hi = [max(p[k] for p in pos) for k in range(3)]
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(data)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(pdata)},
            {"buffer": 0, "byteOffset": len(pdata), "byteLength": len(idata)},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": 3 * len(tris), "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    put(root, "gltf", name + ".glb", glb(doc, data))


def main():
    root = sys.argv[1]
    for mesh in sys.argv[2:]:
        mesh_seeds(root, mesh)
    ply_seeds(root)
    obj_seeds(root)
    gltf_seeds(root)
    hdr_seeds(root)
    scene_seeds(root)
    clean_seeds(root)


if __name__ == "__main__":
    main()
