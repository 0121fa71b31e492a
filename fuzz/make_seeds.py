#!/usr/bin/python3
"""Seed corpora for the fuzz targets, generated from ../shared/data, scenes/ and small hand-written
files (nothing from the data folder is committed). Usage:

    /usr/bin/python3 fuzz/make_seeds.py OUT_DIR [--data DIR] [--scenes DIR]

Writes OUT_DIR/<target>/<name> for mesh_obj, mesh_stl, mesh_ply, mesh_vtp, mesh_vtk, volume_nifti,
volume_mha, volume_nrrd, centerline and scene. The binary formats MedSpring writes itself (VTP
appended, binary STL/PLY/VTK, compressed MetaImage, checkpoints, model packages) come from
medspring_fuzz_seeds (fuzz/make_seeds.cpp); fuzz/make-seeds.sh runs both.
"""
import argparse
import base64
import gzip
import os
import shutil
import struct
import zlib
from pathlib import Path

import numpy as np


def put(out, target, name, data):
    d = Path(out) / target
    d.mkdir(parents=True, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    (d / name).write_bytes(data)


# --- meshes -----------------------------------------------------------------------------------------

def read_obj(path):
    V, F = [], []
    for line in open(path, encoding="utf-8", errors="replace"):
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            V.append([float(x) for x in t[1:4]])
        elif t[0] == "f":
            F.append([int(r.split("/")[0]) - 1 for r in t[1:]])
    return np.array(V), F


def subset(V, F, nfaces):
    """The first nfaces triangles and only the vertices they use, renumbered."""
    F = [f for f in F if len(f) == 3][:nfaces]
    used = sorted({i for f in F for i in f})
    remap = {old: new for new, old in enumerate(used)}
    return V[used], np.array([[remap[i] for i in f] for f in F], dtype=np.int64)


def obj_text(V, F, extra=""):
    s = "# MedSpring fuzz seed\n" + extra
    s += "".join(f"v {x:.6g} {y:.6g} {z:.6g}\n" for x, y, z in V)
    s += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F)
    return s


def stl_ascii(V, F):
    s = "solid seed\n"
    for f in F:
        s += " facet normal 0 0 0\n  outer loop\n"
        s += "".join(f"   vertex {V[i][0]:.6g} {V[i][1]:.6g} {V[i][2]:.6g}\n" for i in f)
        s += "  endloop\n endfacet\n"
    return s + "endsolid seed\n"


def stl_binary(V, F):
    b = b"binary seed".ljust(80, b" ") + struct.pack("<I", len(F))
    for f in F:
        b += struct.pack("<3f", 0, 0, 0)
        for i in f:
            b += struct.pack("<3f", *V[i])
        b += b"\0\0"
    return b


def ply(V, F, fmt):
    head = f"ply\nformat {fmt} 1.0\ncomment seed\nelement vertex {len(V)}\n"
    head += "property float x\nproperty float y\nproperty float z\n"
    head += f"element face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n"
    if fmt == "ascii":
        body = "".join(f"{x:.6g} {y:.6g} {z:.6g}\n" for x, y, z in V)
        body += "".join(f"3 {a} {b} {c}\n" for a, b, c in F)
        return (head + body).encode()
    e = "<" if fmt == "binary_little_endian" else ">"
    body = b"".join(struct.pack(e + "3f", *v) for v in V)
    body += b"".join(struct.pack(e + "B3i", 3, *f) for f in F)
    return head.encode() + body


def vtk_legacy(V, F, new_cells=False, lines=None, arrays=True):
    s = f"# vtk DataFile Version {'5.1' if new_cells else '3.0'}\nseed\nASCII\nDATASET POLYDATA\n"
    s += f"POINTS {len(V)} float\n" + "".join(f"{x:.6g} {y:.6g} {z:.6g}\n" for x, y, z in V)
    if new_cells:  # VTK 5.1 layout
        s += f"POLYGONS {len(F) + 1} {3 * len(F)}\nOFFSETS vtktypeint64\n"
        s += " ".join(str(3 * k) for k in range(len(F) + 1)) + "\nCONNECTIVITY vtktypeint64\n"
        s += " ".join(str(i) for f in F for i in f) + "\n"
    else:
        s += f"POLYGONS {len(F)} {4 * len(F)}\n" + "".join(f"3 {a} {b} {c}\n" for a, b, c in F)
    if lines:
        s += f"LINES {len(lines)} {sum(len(l) + 1 for l in lines)}\n"
        s += "".join(f"{len(l)} " + " ".join(map(str, l)) + "\n" for l in lines)
    if arrays:
        s += f"POINT_DATA {len(V)}\nSCALARS height float 1\nLOOKUP_TABLE default\n"
        s += "".join(f"{v[2]:.6g}\n" for v in V)
    return s


def vtp_xml(V, cells, kind="Polys", point_arrays=(), binary=False):
    """VTK XML PolyData with inline ascii or base64 (header UInt32) data."""

    def array(name, dtype, values, ncomp=1):
        attrs = f'type="{dtype}"' + (f' Name="{name}"' if name else "") + f' NumberOfComponents="{ncomp}"'
        values = np.asarray(values)
        if binary:
            np_t = {"Float32": "<f4", "Float64": "<f8", "Int64": "<i8", "Int32": "<i4"}[dtype]
            raw = values.astype(np_t).tobytes()
            text = base64.b64encode(struct.pack("<I", len(raw)) + raw).decode()
            return f'<DataArray {attrs} format="binary">{text}</DataArray>\n'
        text = " ".join(f"{x:.9g}" if dtype.startswith("Float") else str(int(x)) for x in values.ravel())
        return f'<DataArray {attrs} format="ascii">{text}</DataArray>\n'

    conn = [i for c in cells for i in c]
    offs = np.cumsum([len(c) for c in cells])
    counts = {"Verts": 0, "Lines": 0, "Strips": 0, "Polys": 0}
    counts[kind] = len(cells)
    s = '<?xml version="1.0"?>\n<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian" header_type="UInt32">\n<PolyData>\n'
    s += f'<Piece NumberOfPoints="{len(V)}" NumberOfVerts="{counts["Verts"]}" NumberOfLines="{counts["Lines"]}" NumberOfStrips="{counts["Strips"]}" NumberOfPolys="{counts["Polys"]}">\n'
    s += "<PointData>\n" + "".join(array(n, "Float64", v, 1) for n, v in point_arrays) + "</PointData>\n"
    s += "<Points>\n" + array(None, "Float32", np.asarray(V), 3) + "</Points>\n"
    s += f"<{kind}>\n" + array("connectivity", "Int64", conn) + array("offsets", "Int64", offs) + f"</{kind}>\n"
    s += "</Piece>\n</PolyData>\n</VTKFile>\n"
    return s


def mesh_seeds(out, data):
    kidney = Path(data) / "kidney_left_hubmap_vhm.obj"
    aorta = Path(data) / "aorta_totalseg_ct.obj"
    sets = []
    if kidney.is_file():
        V, F = read_obj(kidney)
        sets += [("kidney40", *subset(V, F, 40)), ("kidney300", *subset(V, F, 300))]
        # a truncation of the real file (cut mid-line: the reader must reject or read the prefix)
        raw = kidney.read_bytes()
        put(out, "mesh_obj", "kidney_head.obj", raw[:6000])
    if aorta.is_file():
        V, F = read_obj(aorta)
        sets += [("aorta60", *subset(V, F, 60))]
    # a tetrahedron by hand
    sets += [("tetra", np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]),
              np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))]
    for name, V, F in sets:
        put(out, "mesh_obj", f"{name}.obj", obj_text(V, F))
        put(out, "mesh_stl", f"{name}_ascii.stl", stl_ascii(V, F))
        put(out, "mesh_stl", f"{name}_binary.stl", stl_binary(V, F))
        put(out, "mesh_ply", f"{name}_ascii.ply", ply(V, F, "ascii"))
        put(out, "mesh_ply", f"{name}_le.ply", ply(V, F, "binary_little_endian"))
        put(out, "mesh_ply", f"{name}_be.ply", ply(V, F, "binary_big_endian"))
        put(out, "mesh_vtk", f"{name}.vtk", vtk_legacy(V, F))
        put(out, "mesh_vtk", f"{name}_v51.vtk", vtk_legacy(V, F, new_cells=True, arrays=False))
        put(out, "mesh_vtp", f"{name}_ascii.vtp", vtp_xml(V, F.tolist(), point_arrays=[("z", V[:, 2])]))
        put(out, "mesh_vtp", f"{name}_base64.vtp", vtp_xml(V, F.tolist(), binary=True))
    # OBJ features: texture/normal references, negative indices, quads and polygons, lines, groups
    put(out, "mesh_obj", "features.obj",
        "mtllib none.mtl\no cube\ng side\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 -1\nvn 0 0 1\nusemtl m\ns 1\n"
        "f 1/1/1 4/2/1 3/3/1 2/1/1\nf 5//2 6//2 7//2 8//2\nf -8 -7 -3 -4\nf 2 3 7 6\nf 3 4 8 7 # quad\n"
        "f 4/1 1/2 5/3 8/1\nl 1 7\np 2\n")
    put(out, "mesh_vtk", "strips_lines.vtk",
        "# vtk DataFile Version 2.0\nstrip\nASCII\nDATASET POLYDATA\nPOINTS 6 double\n"
        "0 0 0 1 0 0 0 1 0 1 1 0 0 2 0 1 2 0\nTRIANGLE_STRIPS 1 7\n6 0 1 2 3 4 5\nLINES 1 3\n2 0 5\n"
        "VERTICES 1 2\n1 3\n")
    put(out, "mesh_ply", "quad_colors.ply",
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
        "property list uchar uint vertex_indices\nend_header\n0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n"
        "0 1 0 9 9 9\n4 0 1 2 3\n")


# --- centerlines ------------------------------------------------------------------------------------

def centerline_seeds(out, data):
    real = Path(data) / "vmr-0159-aorta-centerline.vtp"
    if real.is_file():
        put(out, "centerline", "vmr0159.vtp", real.read_bytes())
    t = np.linspace(0, 1, 9)
    P = np.stack([10 * t, np.sin(3 * t), np.zeros_like(t)], axis=1)
    R = 0.3 + 0.1 * t
    lines = [list(range(0, 6)), list(range(4, 9))]
    put(out, "centerline", "two_lines_ascii.vtp",
        vtp_xml(P, lines, kind="Lines", point_arrays=[("MaximumInscribedSphereRadius", R)]))
    put(out, "centerline", "two_lines_base64.vtp",
        vtp_xml(P, lines, kind="Lines", point_arrays=[("MaximumInscribedSphereRadius", R)], binary=True))
    s = "# vtk DataFile Version 3.0\ncenterline\nASCII\nDATASET POLYDATA\n"
    s += f"POINTS {len(P)} double\n" + "".join(f"{x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in P)
    s += f"LINES 2 {len(lines[0]) + len(lines[1]) + 2}\n"
    s += "".join(f"{len(l)} " + " ".join(map(str, l)) + "\n" for l in lines)
    s += f"POINT_DATA {len(P)}\nSCALARS MaximumInscribedSphereRadius double 1\nLOOKUP_TABLE default\n"
    s += "".join(f"{r:.9g}\n" for r in R)
    put(out, "centerline", "two_lines.vtk", s)


# --- volumes ----------------------------------------------------------------------------------------

NIFTI_TYPES = {np.uint8: (2, 8), np.int16: (4, 16), np.int32: (8, 32), np.float32: (16, 32),
               np.float64: (64, 64), np.uint16: (512, 16)}


def nifti1(vol, dtype, affine=None, qform=False, slope=0.0, inter=0.0):
    vol = np.asarray(vol, dtype=dtype)
    code, bits = NIFTI_TYPES[dtype]
    h = bytearray(348)
    struct.pack_into("<i", h, 0, 348)
    struct.pack_into("<8h", h, 40, 3, *vol.shape, 1, 1, 1, 1)
    struct.pack_into("<hh", h, 70, code, bits)
    A = np.eye(4) if affine is None else affine
    sp = np.linalg.norm(A[:3, :3], axis=0)
    struct.pack_into("<8f", h, 76, 1.0, *sp, 1, 1, 1, 1)
    struct.pack_into("<f", h, 108, 352.0)
    struct.pack_into("<ff", h, 112, slope, inter)
    struct.pack_into("<b", h, 123, 10)  # xyzt_units: mm, s
    if qform:
        struct.pack_into("<hh", h, 252, 1, 0)
        struct.pack_into("<6f", h, 256, 0.0, 0.0, 1.0, *A[:3, 3])  # 180 deg about z
    else:
        struct.pack_into("<hh", h, 252, 0, 2)
        for r in range(3):
            struct.pack_into("<4f", h, 280 + 16 * r, *A[r])
    h[344:348] = b"n+1\0"
    return bytes(h) + b"\0" * 4 + vol.tobytes(order="F")


def nifti2(vol, dtype):
    vol = np.asarray(vol, dtype=dtype)
    code, bits = NIFTI_TYPES[dtype]
    h = bytearray(540)
    struct.pack_into("<i", h, 0, 540)
    h[4:12] = b"n+2\0\r\n\x1a\n"
    struct.pack_into("<hh", h, 12, code, bits)
    struct.pack_into("<8q", h, 16, 3, *vol.shape, 1, 1, 1, 1)
    struct.pack_into("<8d", h, 104, 1, 0.8, 0.8, 2.0, 1, 1, 1, 1)
    struct.pack_into("<q", h, 168, 544)
    struct.pack_into("<ii", h, 344, 0, 1)  # qform_code, sform_code
    for r, row in enumerate([[0.8, 0, 0, -5], [0, 0.8, 0, 3], [0, 0, 2.0, 1]]):
        struct.pack_into("<4d", h, 400 + 32 * r, *row)
    return bytes(h) + b"\0" * 4 + vol.tobytes(order="F")


def volume_seeds(out, data):
    mask = Path(data) / "aorta_totalseg_mask.nii.gz"
    if mask.is_file():
        b = gzip.open(mask).read()
        put(out, "volume_nifti", "aorta_head.nii", b[:352 + 4096])  # a truncation of the real file
        dims = struct.unpack("<3h", b[42:48])
        off = int(struct.unpack("<f", b[108:112])[0])
        vol = np.frombuffer(b[off:off + int(np.prod(dims))], dtype=np.uint8).reshape(dims, order="F")
        nz = np.argwhere(vol > 0)
        c = nz[len(nz) // 2]
        crop = vol[c[0] - 4:c[0] + 4, c[1] - 4:c[1] + 3, c[2] - 3:c[2] + 3]
        srow = np.array([struct.unpack("<4f", b[280 + 16 * r:296 + 16 * r]) for r in range(3)] + [[0, 0, 0, 1]])
        put(out, "volume_nifti", "aorta_crop.nii", nifti1(crop, np.uint8, srow))
        put(out, "volume_nifti", "aorta_crop.nii.gz", gzip.compress(nifti1(crop, np.uint8, srow), mtime=0))
    else:
        crop = (np.indices((8, 7, 6)).sum(axis=0) % 3 == 0).astype(np.uint8)
    lab = crop.astype(np.int16) * 3
    put(out, "volume_nifti", "int16_qform.nii", nifti1(lab, np.int16, np.diag([1.5, 1.5, 2.0, 1]), qform=True))
    put(out, "volume_nifti", "float_scaled.nii", nifti1(crop * 0.5, np.float32, slope=2.0, inter=0.0))
    put(out, "volume_nifti", "nifti2.nii", nifti2(crop, np.uint16))

    # MetaImage: raw uchar, short with a rotation, float, compressed
    def mha(vol, etype, np_t, extra="", compress=False):
        raw = np.asarray(vol, dtype=np_t).tobytes(order="F")
        body = zlib.compress(raw) if compress else raw
        h = f"ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
        if compress:
            h += f"CompressedData = True\nCompressedDataSize = {len(body)}\n"
        h += extra
        h += f"ElementSpacing = 0.5 0.6 1.5\nDimSize = {vol.shape[0]} {vol.shape[1]} {vol.shape[2]}\n"
        h += f"ElementType = {etype}\nElementDataFile = LOCAL\n"
        return h.encode() + body
    put(out, "volume_mha", "uchar.mha", mha(crop, "MET_UCHAR", np.uint8, "Offset = -10 4 2.5\n"))
    put(out, "volume_mha", "short_rot.mha", mha(lab, "MET_SHORT", "<i2",
        "TransformMatrix = 0 1 0 -1 0 0 0 0 1\nOffset = 1 2 3\nAnatomicalOrientation = RAI\n"))
    put(out, "volume_mha", "float.mha", mha(crop, "MET_FLOAT", "<f4"))
    put(out, "volume_mha", "uchar_zlib.mha", mha(crop, "MET_UCHAR", np.uint8, compress=True))

    # NRRD: raw LPS with directions, gzip RAS, ascii, a first axis of <= 9 samples
    def nrrd(vol, typ, np_t, enc, space="left-posterior-superior", dirs="(0.5,0,0) (0,0.5,0) (0,0,1.5)"):
        raw = np.asarray(vol, dtype=np_t).tobytes(order="F")
        h = f"NRRD0004\n# seed\ntype: {typ}\ndimension: 3\nspace: {space}\n"
        h += f"sizes: {vol.shape[0]} {vol.shape[1]} {vol.shape[2]}\nspace directions: {dirs}\n"
        h += "kinds: domain domain domain\nendian: little\n" f"encoding: {enc}\nspace origin: (-1,2.5,30)\n\n"
        if enc == "raw":
            body = raw
        elif enc == "gzip":
            body = gzip.compress(raw, mtime=0)
        else:
            body = (" ".join(str(int(x)) for x in np.asarray(vol).ravel(order="F")) + "\n").encode()
        return h.encode() + body
    put(out, "volume_nrrd", "uchar_raw.nrrd", nrrd(crop, "uchar", np.uint8, "raw"))
    put(out, "volume_nrrd", "short_gzip_ras.nrrd",
        nrrd(lab, "short", "<i2", "gzip", space="right-anterior-superior", dirs="(0,0.5,0) (0.5,0,0) (0,0,1)"))
    put(out, "volume_nrrd", "int_ascii.nrrd", nrrd(lab, "int", "<i4", "ascii"))
    wide = np.zeros((12, 3, 2), dtype=np.uint8)
    wide[3:7, 1, :] = 2
    put(out, "volume_nrrd", "first_axis_12.nrrd", nrrd(wide, "uint8", np.uint8, "raw"))


# --- scenes -----------------------------------------------------------------------------------------

SCENES = {
    "tube_surface.json": '{"model": {"kind": "surface", "source": {"phantom": {"name": "tube", "rings": 6, '
                         '"spokes": 8, "spacing": 2.0, "radius": 2.5}}, "nonlinear": false, "parameters": '
                         '{"k": 0.3, "k_r": 0.01, "fixed": [0, 1, 2]}}, "loads": [{"ring": 3, "spoke": 2, '
                         '"direction": [0, 0, -1], "magnitude": 0.2, "t_release": null, "ramp_down": true}], '
                         '"integrator": {"method": "implicit_euler", "dt": 1.0, "substep": false, "safety": 0.9, '
                         '"max_substeps": 16}, "duration": 50, "local": {"enabled": true, "stiffness": '
                         '"linearized", "k_loc": 0.1, "patch_nodes": 9, "half_width": 1, "cache": false, '
                         '"guard": true}, "record": {"every": 1, "frames": false, "nodes": [5, 6], '
                         '"key_times": [0, 25]}}',
    "kidney_surface.json": '{"name": "k", "description": "surface kidney", "model": {"kind": "surface", '
                           '"source": {"phantom": "kidney"}, "parameters": {"duffing": {"mode": "strain", '
                           '"eta": 2, "soft": true}}}, "loads": [{"point": [1, 2, 3], "direction": '
                           '"inward_normal", "magnitude": 1}], "local": true}',
    "kidney_hybrid_atoms.json": '{"model": {"kind": "hybrid", "source": {"phantom": "kidney"}, "atoms": 12, '
                                '"parameters": {"k_surf": 0.5, "k_spoke": 0.3, "k_cl": 1.0, '
                                '"spokes_per_atom": 2, "atom_mass": 2, "duffing": {"length": 3}}}, "loads": '
                                '[{"node": 10, "direction": "towards_atom", "atom": 3, "magnitude": 0.5, '
                                '"t_on": 5, "t_ramp": 0}], "record": {"atoms": [0, 11]}}',
    "vessel_helix.json": '{"model": {"kind": "smrm", "source": {"phantom": {"name": "vessel", "path": "helix", '
                         '"cross_section": "non_planar"}}, "atoms": 10, "parameters": {"spokes": 8, '
                         '"k_b": 0.01, "fix_first": false, "frame_mode": "rmf", "frame_anchor": "one_end"}}, '
                         '"loads": [{"ring": 5, "spoke": 3, "direction": "inward_normal", "magnitude": 0.1}]}',
    "mesh_source.json": '{"model": {"kind": "hybrid", "source": {"mesh": {"file": "mesh.obj", "unit": "cm"}}, '
                        '"surface_nodes": 100}, "loads": []}',
    "segmentation_source.json": '{"model": {"kind": "surface", "source": {"segmentation": {"file": '
                                '"${MEDSPRING_DATA}/aorta_totalseg_mask.nii.gz", "label": 1}}}}',
    "centerline_mesh.json": '{"model": {"kind": "smrm", "source": {"centerline": {"file": "line.vtp", "unit": '
                            '"mm", "branch": 1, "radius_array": "r", "range_mm": [5, 40]}, "mesh": {"file": '
                            '"mesh.stl", "unit": "um"}}}}',
}


def scene_seeds(out, scenes):
    for d in [Path(scenes), Path(scenes) / "phantom"]:
        if d.is_dir():
            for f in sorted(d.glob("*.json")):
                put(out, "scene", f"{d.name}_{f.name}", f.read_bytes())
    for name, text in SCENES.items():
        put(out, "scene", name, text)


def main():
    here = Path(__file__).resolve().parent
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--data", default=os.environ.get("MEDSPRING_DATA") or str(here.parent.parent / "shared" / "data"))
    ap.add_argument("--scenes", default=str(here.parent / "scenes"))
    a = ap.parse_args()
    if not Path(a.data).is_dir():
        print(f"make_seeds.py: no data folder {a.data}: seeds from the real anatomy left out")
    mesh_seeds(a.out, a.data)
    centerline_seeds(a.out, a.data)
    volume_seeds(a.out, a.data)
    scene_seeds(a.out, a.scenes)
    n = sum(1 for _ in Path(a.out).rglob("*") if _.is_file())
    print(f"make_seeds.py: {n} files under {a.out}")


if __name__ == "__main__":
    main()
