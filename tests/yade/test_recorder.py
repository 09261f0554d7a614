"""MpmHdf5Recorder writes what the points hold, an XDMF index that points at real datasets, and
never a non-finite value; yade_mpm.results reads it back."""
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

import yade.wrapper as w
from yade import O

import yade_mpm
from yade_mpm import results

G = (0.0, 0.0, -9.81)


def scene(tmp_path, period):
    soil, water = w.MpmSoilMat(), w.MpmWaterMat(bulkModulus=2.2e8)
    O.materials.append([soil, water])
    solid, fluid = yade_mpm.saturated_block((0, 0, 0), (0.1, 0.1, 0.3), 0.05, soil, water, gravity=G)
    O.bodies.append([solid, fluid])
    O.engines = [w.MpmTwoPhaseEngine(label="mpm", gravity=G, domainMin=(0, 0, 0), domainMax=(0.1, 0.1, 0.3), cellSize=0.05,
                                     solidWalls=("slip",) * 4 + ("fixed", "free"), waterWalls=("impermeable",) * 5 + ("drained",)),
                 w.MpmHdf5Recorder(label="recorder", file=str(tmp_path / "run.h5"), iterPeriod=period)]
    O.dt = 1e-4
    return solid.shape, fluid.shape


def test_records_read_back_exactly(tmp_path):
    solid, fluid = scene(tmp_path, 5)
    O.run(16, True)
    records = results.read(str(tmp_path / "run.h5"))
    assert [r.iteration for r in records] == [0, 5, 10, 15]
    assert records[-1].time == pytest.approx(16 * 1e-4)  # recorded after the MPM step of iteration 15
    last = records[-1]
    s, f = last.sets["solid_0"], last.sets["water_1"]
    assert np.array_equal(s["position"], solid.pos) and np.array_equal(s["velocity"], solid.vel)
    assert np.array_equal(s["stress"], solid.stress) and np.array_equal(s["porosity"], solid.porosity)
    assert np.array_equal(f["porePressure"], fluid.porePressure) and np.array_equal(f["position"], fluid.pos)
    grid = last.grid
    assert grid["solidMass"].shape == (6 + 3, 2 + 3, 2 + 3)  # (nz, ny, nx): domain cells + 3 nodes per axis
    assert grid["solidVelocity"].shape == (9, 5, 5, 3)
    assert grid["solidMass"].sum() == pytest.approx(solid.mass.sum(), rel=1e-12)  # P2G conserves mass
    assert np.allclose(grid["origin"], [-0.05, -0.05, -0.05]) and grid["spacing"] == 0.05
    assert O.engines[1].records == 4


def test_xdmf_index_points_at_existing_datasets_with_matching_shapes(tmp_path):
    scene(tmp_path, 3)
    O.run(7, True)
    tree = ET.parse(str(tmp_path / "run.xmf"))
    times = [float(t.get("Value")) for t in tree.iter("Time")]
    assert len(times) == 3 and times == sorted(times)
    items = [d for d in tree.iter("DataItem") if d.get("Format") == "HDF"]
    assert len(items) > 10
    with h5py.File(str(tmp_path / "run.h5"), "r") as f:
        for item in items:
            filename, path = item.text.split(":")
            assert filename == "run.h5"
            dims = [int(x) for x in item.get("Dimensions").split()]
            assert int(np.prod(f[path].shape)) == int(np.prod(dims)), path


def test_non_finite_values_are_refused_and_earlier_records_survive(tmp_path):
    solid, fluid = scene(tmp_path, 1)
    O.engines = [O.engines[1]]  # the recorder alone: nothing else checks the points
    O.run(2, True)
    p = fluid.porePressure
    p[3] = np.nan
    fluid.porePressure = p
    with pytest.raises(RuntimeError, match=r"refusing to record a non-finite value: water_1/porePressure row 3"):
        O.step()  # raises in this thread; O.run(1, True) may miss an error of YADE's run thread
    records = results.read(str(tmp_path / "run.h5"))
    assert len(records) == 2 and all(np.isfinite(r.sets["water_1"]["porePressure"]).all() for r in records)


def test_recorder_attributes_and_period_validation(tmp_path):
    with pytest.raises(ValueError, match=r"iterPeriod = 0 is outside the valid range"):
        w.MpmHdf5Recorder(iterPeriod=0)


def test_recorder_files_are_checked_before_anything_advances(tmp_path):
    """Issue 17 item 5: a file the recorder cannot or must not write is refused when it is set, or at
    the first step before the MPM engine advances (mpmTime stays equal to O.time): a missing
    directory, an .xmf name (the index goes next to the HDF5 file), an existing file that is not a
    recorder's HDF5 (never overwritten), two recorders on one file. Policy: an earlier run's HDF5 of a
    recorder is replaced by a recorder that has not recorded yet."""
    missing = tmp_path / "missing" / "dir" / "run.h5"
    with pytest.raises(ValueError, match=r"MpmHdf5Recorder.file = '.*run.h5': its directory '.*missing/dir' does not exist"):
        w.MpmHdf5Recorder(file=str(missing))
    with pytest.raises(ValueError, match=r"MpmHdf5Recorder.file = '.*run.xmf': the XDMF index is written next to the HDF5 file"):
        w.MpmHdf5Recorder(file=str(tmp_path / "run.xmf"))
    foreign = tmp_path / "run.h5"
    foreign.write_text("my notes, not an HDF5 file")
    solid, fluid = scene(tmp_path, 1)
    engine = O.engines[0]
    with pytest.raises(ValueError, match=r"MpmHdf5Recorder.file = '.*run.h5' exists and is not an MpmHdf5Recorder's HDF5 file: refusing to overwrite it"):
        O.step()
    assert foreign.read_text() == "my notes, not an HDF5 file"
    assert engine.stepsDone == 0 and engine.mpmTime == O.time == 0 and O.iter == 0
    O.engines = O.engines + [w.MpmHdf5Recorder(label="second", file=str(tmp_path / "." / "other.h5"), iterPeriod=1),
                             w.MpmHdf5Recorder(label="third", file=str(tmp_path / "other.h5"))]
    O.engines[1].file = str(tmp_path / "first.h5")
    with pytest.raises(ValueError, match=r"other.h5' is also the file of O.engines\[3\] \(label 'third'\): two recorders would write one file"):
        O.step()
    assert engine.stepsDone == 0 and engine.mpmTime == O.time == 0
    O.engines = O.engines[:3]
    O.run(2, True)
    assert engine.mpmTime == pytest.approx(O.time) and O.engines[1].records == 2 == O.engines[2].records
    # an earlier run's file: a fresh recorder replaces it
    O.engines = O.engines[:1] + [w.MpmHdf5Recorder(file=str(tmp_path / "first.h5"), iterPeriod=1)]
    O.run(1, True)
    assert len(results.read(str(tmp_path / "first.h5"))) == 1


PARAVIEW_CHECK = """
import json, sys
from paraview.simple import OpenDataFile
from paraview import servermanager
reader = OpenDataFile(sys.argv[1])
reader.UpdatePipelineInformation()
times = list(reader.TimestepValues)
blocks = []
def walk(data):
    if data.IsA("vtkMultiBlockDataSet"):
        for i in range(data.GetNumberOfBlocks()):
            walk(data.GetBlock(i))
    elif data.IsA("vtkMultiPieceDataSet"):
        for i in range(data.GetNumberOfPieces()):
            walk(data.GetPiece(i))
    else:
        arrays = data.GetPointData()
        blocks.append([data.GetClassName(), data.GetNumberOfPoints(), data.GetNumberOfCells(),
                       sorted(arrays.GetArrayName(i) for i in range(arrays.GetNumberOfArrays()))])
reader.UpdatePipeline(times[-1])
walk(servermanager.Fetch(reader))
print("PARAVIEW", json.dumps({"reader": reader.GetXMLName(), "times": times, "blocks": blocks}))
"""


def test_paraview_default_reader_shows_one_cell_per_point(tmp_path):
    """Issue 17 item 8: Debian's ParaView (pvpython, the reader OpenDataFile picks for .xmf,
    Xdmf3ReaderS) loads every time step, shows N cells for the N points of each set (one Polyvertex
    cell per point: without the connectivity it made one cell, or none, of them all) with their
    fields, and the grid."""
    import json
    import shutil
    import subprocess
    pvpython = shutil.which("pvpython")
    assert pvpython, "pvpython not found: scripts/install-deps.sh installs Debian's paraview"
    solid, fluid = scene(tmp_path, 5)
    O.run(11, True)
    script = tmp_path / "check.py"
    script.write_text(PARAVIEW_CHECK)
    done = subprocess.run([pvpython, str(script), str(tmp_path / "run.xmf")], capture_output=True, text=True, timeout=120,
                          env={"HOME": str(tmp_path), "PATH": "/usr/bin:/bin"}, stdin=subprocess.DEVNULL)
    lines = [l for l in done.stdout.splitlines() if l.startswith("PARAVIEW ")]
    assert lines, done.stdout[-2000:] + done.stderr[-2000:]
    seen = json.loads(lines[0][len("PARAVIEW "):])
    assert seen["reader"] == "Xdmf3ReaderS"
    assert seen["times"] == pytest.approx([r.time for r in results.read(str(tmp_path / "run.h5"))])
    sets = sorted((count, cells) for kind, count, cells, _ in seen["blocks"] if kind == "vtkUnstructuredGrid")
    assert sets == sorted([(solid.count, solid.count), (fluid.count, fluid.count)])  # N cells for the N points of each set
    assert "vtkUniformGrid" in [b[0] for b in seen["blocks"]]
    arrays = [b[3] for b in seen["blocks"] if b[0] == "vtkUnstructuredGrid"]
    assert ["porePressure", "porosity", "velocity", "volume"] in arrays
    assert any({"stress", "velocity", "porosity"} <= set(a) for a in arrays)


def test_a_reloaded_recorder_does_not_write_over_its_records(tmp_path):
    """After O.save/O.load a recorder that has recorded refuses, before the engine advances, to start
    its file again (it would replace the records); a new file name continues."""
    scene(tmp_path, 1)
    O.run(2, True)
    O.saveTmp("recorded")
    O.loadTmp("recorded")
    engine, recorder = O.engines[0], O.engines[1]
    steps, time = engine.stepsDone, O.time
    with pytest.raises(ValueError, match=r"MpmHdf5Recorder.file = '.*run.h5' already holds 2 records of this scene"):
        O.step()
    assert engine.stepsDone == steps and O.time == time and engine.mpmTime == pytest.approx(O.time)
    assert len(results.read(str(tmp_path / "run.h5"))) == 2
    recorder.file = str(tmp_path / "continued.h5")
    O.step()
    assert len(results.read(str(tmp_path / "continued.h5"))) == 1
