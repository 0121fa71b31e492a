"""Mesh, centerline and volume I/O on the real data (VTK at the edge)."""

import json

import numpy as np
import pytest

import medspring as ms
from conftest import data_file


def test_real_kidney_mesh_reads_in_metres_and_scales_to_mm():
    r = ms.read_mesh_with_report(data_file("kidney_left_hubmap_vhm.obj"), unit="m")
    assert r.format == "OBJ" and r.scale_to_mm == 1000.0
    assert r.mesh.V.shape == (5002, 3) and r.report.closed and r.report.manifold
    size = r.mesh.V.max(axis=0) - r.mesh.V.min(axis=0)
    np.testing.assert_allclose(size, [75.9, 106.7, 82.7], atol=0.1)  # data README, mm


def test_aorta_centerlines_read_four_branches_in_mm():
    lines = ms.read_centerlines(data_file("vmr-0159-aorta-centerline.vtp"), unit=ms.LengthUnit.Centimetre)
    assert [len(line) for line in lines] == [457, 401, 581, 431]
    assert lines[0].points.dtype == np.float64 and lines[0].radii.shape == (457,)
    radii = np.concatenate([line.radii for line in lines])
    assert radii.min() == pytest.approx(2.61, abs=0.01) and radii.max() == pytest.approx(14.83, abs=0.01)


def test_aorta_mask_volume_reads_with_its_spacing():
    vol = ms.read_label_volume(data_file("aorta_totalseg_mask.nii.gz"))
    assert vol.dims == (120, 126, 164) and np.allclose(vol.spacing, 1.5)
    assert vol.data.shape == (120, 126, 164) and int((vol.data == 1).sum()) == 72810
    mask = ms.select_label(vol, 1)
    assert mask.data.dtype == np.uint8 and int(mask.data.sum()) == 72810


def test_written_vtp_reads_back_identically(tmp_path):
    mesh = ms.kidney_phantom()
    path = tmp_path / "kidney.vtp"
    ms.write_vtp(path, mesh, {"height": mesh.V[:, 2].copy(), "normal": ms.vertex_normals(mesh)})
    back = ms.read_mesh(path)
    assert np.array_equal(back.V, mesh.V) and np.array_equal(back.F, mesh.F)


def test_describe_file_summarises_as_json():
    info = ms.describe_file(data_file("kidney_left_hubmap_vhm.obj"), unit="m")
    assert info.kind == "mesh" and info.format == "OBJ"
    j = json.loads(info.to_json())
    assert "5002" in info.text() and isinstance(j, dict)


def test_data_file_finds_the_data_folder():
    assert ms.data_file("kidney_left_hubmap_vhm.obj") == data_file("kidney_left_hubmap_vhm.obj").resolve()
    with pytest.raises(ms.IoError, match="not found"):
        ms.data_file("no_such_file.obj")
