"""VTU files (critical angle and animation frames): zlib-compressed float32 VTK XML (appended raw
binary) that meshio AND VTK's own reader read, with every array, equal to the float64 solution to float32 precision."""

import meshio
import numpy as np
import pytest

from rigfem.report.vtu import write_frame, write_vtu
from rigfem.tensors import von_mises

ARRAYS = {"displacement": 3, "stress": 6, "von_mises": 1, "safety_factor": 1}


@pytest.fixture(scope="module")
def solved():
    """A P2 cantilever (tests/test_fe_solver_output.py's), two load cases, off the origin (coordinates
    up to 1.1 m: float32's 7 digits against the 1e-6 of the extent)."""
    from fe_shapes import box

    from rigfem.fe import Fixed, SurfaceForce, build_model, solve
    from rigfem.material import get_material

    model = build_model(box(100, 10, 10, 20, 2, 2), get_material("rig_steel"), 2)
    model.mesh.nodes[:] += (1000.0, -300.0, 40.0)
    return solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 0, -100)), SurfaceForce("xmax", (50, 20, 0))])


def _vtk(path):
    import vtk  # a declared test dependency: VTK's own reader, not meshio's
    from vtk.util.numpy_support import vtk_to_numpy

    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(str(path))
    r.Update()
    g = r.GetOutput()
    pd = g.GetPointData()
    arrays = {pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i)) for i in range(pd.GetNumberOfArrays())}
    cells = vtk_to_numpy(g.GetCells().GetConnectivityArray())
    return vtk_to_numpy(g.GetPoints().GetData()), cells, {g.GetCellType(i) for i in range(g.GetNumberOfCells())}, arrays


def _close(got, want, name):
    want = np.asarray(want, float).reshape(got.shape)
    tol = 1e-6 * max(np.abs(want).max(), 1e-30)  # float32: 6e-8 relative; 1e-6 of the field's max
    assert got.dtype == np.float32, name
    assert np.abs(got.astype(float) - want).max() <= tol, name


def _check(path, points, cells, cell_type, vtk_type, want):
    m = meshio.read(path)
    assert [c.type for c in m.cells] == [cell_type] and np.array_equal(m.cells[0].data, cells)
    assert list(m.point_data) == list(ARRAYS)  # every array, its name, in the order ParaView lists them
    vpoints, vcells, vtypes, varrays = _vtk(path)
    assert vtypes == {vtk_type} and np.array_equal(vcells.reshape(cells.shape), cells)
    assert list(varrays) == list(ARRAYS)
    extent = np.abs(points).max()
    for got in (m.points, vpoints):
        assert np.abs(got.astype(float) - points).max() <= 1e-6 * extent
    for name, comps in ARRAYS.items():
        for got in (m.point_data[name], varrays[name]):
            assert got.shape == ((len(points), comps) if comps > 1 else (len(points),)), name
            _close(got, want[name], name)
    return m


def test_critical_vtu(solved, tmp_path):
    c = np.array([0.7, -1.3])
    path = write_vtu(tmp_path / "c.vtu", solved, c, 375.0)
    fm, s = solved.model.mesh, solved.stress(c)
    vm = von_mises(s)
    want = {"displacement": solved.displacement(c), "stress": s, "von_mises": vm,
            "safety_factor": np.minimum(375.0 / np.maximum(vm, 3.75), 100.0)}
    m = _check(path, fm.nodes, fm.elements, "tetra10", 24, want)
    assert np.isclose(m.point_data["von_mises"].max(), vm.max(), rtol=1e-6)  # the report's peak
    raw = fm.nodes.nbytes + fm.elements.nbytes + sum(np.asarray(v).nbytes for v in want.values())
    # float32 + zlib in appended raw binary: ~0.36 x raw; the same in base64 ~0.45, float32 uncompressed 0.67
    assert path.stat().st_size < 0.4 * raw


def test_frame(solved, tmp_path):
    fm, c = solved.model.mesh, np.array([1.0, 0.5])
    n, s = fm.n_vertices, solved.stress(c)[:fm.n_vertices]
    fields = {"displacement": solved.displacement(c)[:n].astype(np.float32), "stress": s.astype(np.float32),
              "von_mises": von_mises(s).astype(np.float32)}  # rigfem.fe.partcase.finish's frame
    path = write_frame(tmp_path / "f_000.vtu", fm.nodes[:n], fm.elements[:, :4], fields, 375.0)
    vm = von_mises(s)
    want = {"displacement": solved.displacement(c)[:n], "stress": s, "von_mises": vm,
            "safety_factor": np.minimum(375.0 / np.maximum(vm, 3.75), 100.0)}
    _check(path, fm.nodes[:n], fm.elements[:, :4], "tetra", 10, want)
