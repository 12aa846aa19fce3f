#!/usr/bin/env python3
"""The ParaView files as the usual tools open them (docs/output.md, ParaView).

    build/py-venv/bin/python test/vtk_files.py [path/to/flexmbs]

Needs meshio and VTK (pip packages `meshio`, `vtk`) beside h5py and numpy:
`make test` makes build/py-venv for it. Runs example scenes of inputs/,
shortened, with `&output vtk` on (binary, the default, and one as text):
the five-body mechanism (a flexible coupler, rigid bodies, chain links,
joints) and its modal variant (the coupler reconstructed from its frame
and modes), the two soft links (two flexible bodies), a hex27 cantilever
whose name needs XML's escapes, a rigid four-bar chain (no mesh, no XDMF)
and a cantilever whose solver gives up (its XDMF file has the records there
are). Every .vtu is read by VTK's vtkXMLUnstructuredGridReader (points,
cells, arrays; the mesh's points and displacement, velocity and stress
against the HDF5 file's /flexible/<name>/..., the bodies against /bodies and
/chains, the joints' reactions against /joints and /drivers) and by meshio
(the same points and arrays, the names in the field data); every .xdmf by
VTK's vtkXdmfReader (every time step of /time, the mesh, displacement,
velocity, stress tensor and von Mises stress at a step against the HDF5
file). hex27's node order is checked against VTK's triquadratic
hexahedron. The last line is `N passed, M failed`; the exit status is
non-zero on failures.
"""
import glob
import os
import re
import subprocess
import sys
import tempfile

import h5py
import meshio
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

passed = 0
failed = 0


def check(name, problem):
    """One test: `problem` is '' (or None) when it passed."""
    global passed, failed
    if problem:
        failed += 1
        print('FAIL vtk/%s: %s' % (name, problem))
    else:
        passed += 1
        print('pass vtk/%s' % name)


def executable():
    if len(sys.argv) > 1:
        return os.path.abspath(sys.argv[1])
    env = dict(os.environ)
    env.setdefault('FPM_FFLAGS', '-I/usr/include/hdf5/serial -I/usr/include/sundials/fortran '
                   '-I/usr/include -I/usr/include/mumps_seq')
    env.setdefault('FPM_CFLAGS', '-I/usr/include/suitesparse -fPIC')
    out = subprocess.run([env.get('FPM', 'fpm'), 'run', '--profile', 'debug', '--runner', 'echo',
                          'flexmbs'], cwd=ROOT, env=env, capture_output=True, text=True).stdout
    lines = out.strip().split('\n')
    return os.path.join(ROOT, lines[-1]) if lines and lines[-1] else ''


def variant(source, target, edits, output):
    """inputs/SOURCE with the (old, new) `edits` and `output` after &output."""
    with open(os.path.join(ROOT, 'inputs', source), encoding='utf-8') as f:
        text = f.read()
    for old, new in edits:
        changed = re.sub(old, new, text, count=1, flags=re.M)
        if changed == text:
            raise RuntimeError('%s: no %r' % (source, old))
        text = changed
    text = re.sub(r'^&output', '&output ' + output + ',', text, count=1, flags=re.M)
    # mesh files are named relative to the scene's folder
    text = text.replace("mesh_file = 'meshes/", "mesh_file = '%s/inputs/meshes/" % ROOT)
    with open(target, 'w', encoding='utf-8') as f:
        f.write(text)


def run(exe, scene, code=0):
    """Run a scene; '' when it ended with `code` and nothing on standard error
    but what a failure says."""
    done = subprocess.run([exe, 'run', scene, '--quiet'], capture_output=True, text=True)
    if done.returncode != code:
        return 'exit %d (want %d): %s' % (done.returncode, code, done.stderr.strip()[-400:])
    if code == 0 and done.stderr:
        return 'standard error: %s' % done.stderr.strip()[-400:]
    return ''


def pvd_files(pvd):
    """(time, part, file) of every data set of a .pvd."""
    with open(pvd, encoding='utf-8') as f:
        text = f.read()
    return [(float(t), int(p), os.path.join(os.path.dirname(pvd), n)) for t, p, n in
            re.findall(r'timestep="([^"]+)" part="(\d)" file="([^"]+)"', text)]


def read_vtu(path):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        raise RuntimeError('VTK cannot read %s' % path)
    return reader.GetOutput()


def arrays(data):
    """Name -> numpy array of a vtkFieldData (point, cell or field data)."""
    return {data.GetAbstractArray(i).GetName(): vtk_to_numpy(data.GetAbstractArray(i))
            for i in range(data.GetNumberOfArrays())}


def names(codes):
    """The names of a UInt8 field data array (each followed by a 0)."""
    return bytes(np.asarray(codes, dtype=np.uint8)).decode().split('\0')[:-1]


def differ(a, b, exact):
    """What differs between two arrays ('' when equal; exact: to the bit)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        return 'shapes %s and %s' % (a.shape, b.shape)
    if exact and np.array_equal(a, b):
        return ''
    scale = max(np.abs(b).max(), 1e-300) if b.size else 1.0
    if not exact and np.abs(a - b).max() <= 1e-14 * scale:
        return ''
    return 'largest difference %.3g (of %.3g)' % (np.abs(a - b).max(), scale)


def check_mesh(grid, h5, k, exact):
    """A mesh file against record k of the HDF5 file: '' or the problem."""
    field = arrays(grid.GetFieldData())
    bodies = names(field['flexible_names'])
    if sorted(bodies) != sorted(h5['flexible']):
        return 'flexible_names %s, HDF5 %s' % (bodies, list(h5['flexible']))
    x, disp, vel, stress, mises, ids = [], [], [], [], [], []
    for b, name in enumerate(bodies, start=1):
        g = h5['flexible'][name]
        x.append(g['reference_nodes'][:] + g['displacement'][k])
        disp.append(g['displacement'][k])
        vel.append(g['velocity'][k])
        stress.append(g['stress'][k])
        mises.append(g['von_mises'][k])
        ids.append(np.full(len(g['connectivity']), b))
    point, cell = arrays(grid.GetPointData()), arrays(grid.GetCellData())
    want_points = {'displacement', 'velocity', 'node_id'}
    want_cells = {'stress', 'von_mises', 'element_id', 'flexible_id'}
    if set(point) != want_points or set(cell) != want_cells:
        return 'arrays %s, %s' % (sorted(point), sorted(cell))
    for what, got, want, bitwise in [
            ('points', vtk_to_numpy(grid.GetPoints().GetData()), np.concatenate(x), False),
            ('displacement', point['displacement'], np.concatenate(disp), exact),
            ('velocity', point['velocity'], np.concatenate(vel), exact),
            ('stress', cell['stress'], np.concatenate(stress), exact),
            ('von_mises', cell['von_mises'], np.concatenate(mises), exact),
            ('flexible_id', cell['flexible_id'], np.concatenate(ids), True)]:
        problem = differ(got, want, bitwise)
        if problem:
            return '%s: %s' % (what, problem)
    if np.abs(np.concatenate(disp)).max() == 0 and k > 0:
        return 'no motion to compare'
    return ''


def check_bodies(grid, h5, k):
    """A bodies' file (rigid bodies, then chain links) against record k."""
    bodies = names(arrays(grid.GetFieldData())['body_names'])
    want = []
    for name in bodies:
        group = 'bodies/' + name if 'bodies/' + name in h5 else 'chains/' + name
        if group not in h5:
            return None        # node frames have no HDF5 group: nothing to compare
        want.append(h5[group + '/position'][k])
    return differ(vtk_to_numpy(grid.GetPoints().GetData()), np.array(want), False)


def check_joints(grid, h5, k):
    """A joints' file's reactions on marker i against /joints, /drivers."""
    joints = names(arrays(grid.GetFieldData())['joint_names'])
    force = arrays(grid.GetPointData()).get('reaction_force')
    if force is None:
        return 'no reaction_force'
    for j, name in enumerate(joints):
        if name in h5:
            problem = differ(force[j], h5[name + '/reaction_force'][k], False)
            if problem:
                return '%s: %s' % (name, problem)
    return ''


def check_meshio(path, grid):
    """meshio reads the file: the points, cells and arrays VTK reads."""
    mesh = meshio.read(path)
    if len(mesh.points) != grid.GetNumberOfPoints():
        return '%d points, VTK %d' % (len(mesh.points), grid.GetNumberOfPoints())
    if sum(len(c.data) for c in mesh.cells) != grid.GetNumberOfCells():
        return 'cells %s' % mesh.cells
    problem = differ(mesh.points, vtk_to_numpy(grid.GetPoints().GetData()), True)
    if problem:
        return 'points: ' + problem
    point = arrays(grid.GetPointData())
    if set(mesh.point_data) != set(point):
        return 'point data %s, VTK %s' % (sorted(mesh.point_data), sorted(point))
    for name, values in mesh.point_data.items():
        problem = differ(np.asarray(values).reshape(point[name].shape), point[name], True)
        if problem:
            return name + ': ' + problem
    field = arrays(grid.GetFieldData())
    for name, codes in mesh.field_data.items():
        if names(codes) != names(field[name]):
            return 'field data %s: %s' % (name, names(codes))
    return ''


def check_vtu_files(exe, label, pvd, h5_path, exact=True):
    """Every file of a .pvd by VTK and meshio, against the HDF5 file."""
    h5 = h5py.File(h5_path, 'r')
    times = list(h5['time'][:])
    problems = {'vtk': [], 'meshio': [], 'values': []}
    parts = set()
    for t, part, path in pvd_files(pvd):
        parts.add(part)
        k = times.index(t)
        try:
            grid = read_vtu(path)
        except RuntimeError as e:
            problems['vtk'].append(str(e))
            continue
        try:
            problem = check_meshio(path, grid)
        except Exception as e:         # meshio's ReadError and the like
            problem = '%s: %s' % (type(e).__name__, e)
        if problem:
            problems['meshio'].append('%s: %s' % (os.path.basename(path), problem))
        check_part = {0: lambda: check_mesh(grid, h5, k, exact),
                      1: lambda: check_bodies(grid, h5, k),
                      2: lambda: check_joints(grid, h5, k)}[part]
        problem = check_part()
        if problem:
            problems['values'].append('%s: %s' % (os.path.basename(path), problem))
    count = len(pvd_files(pvd))
    check(label + '-vtk-reads-every-vtu', '; '.join(problems['vtk'][:3]) if count else 'no files')
    check(label + '-meshio-reads-every-vtu', '; '.join(problems['meshio'][:3]))
    check(label + '-vtu-values-are-hdf5', '; '.join(problems['values'][:3]))
    return parts


def read_xdmf(path):
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(path)
    reader.UpdateInformation()
    info = reader.GetOutputInformation(0)
    key = vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS()
    steps = list(info.Get(key)) if info.Has(key) else []
    return reader, steps


def xdmf_blocks(reader, t):
    """The blocks (name -> data set) at time t."""
    reader.UpdateTimeStep(t)
    output = reader.GetOutputDataObject(0)
    blocks = {}
    it = output.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        name = it.GetCurrentMetaData().Get(vtk.vtkCompositeDataSet.NAME())
        blocks[re.sub(r'\[\d+\]$', '', name)] = it.GetCurrentDataObject()
        it.GoToNextItem()
    return blocks


def tensor(stress):
    """xx, yy, zz, xy, yz, xz per row as 3 x 3 matrices, row by row."""
    xx, yy, zz, xy, yz, xz = stress.T
    return np.stack([xx, xy, xz, xy, yy, yz, xz, yz, zz], axis=1)


def check_xdmf(label, h5_path, records=None):
    """The XDMF file beside an HDF5 result, by VTK's XDMF reader."""
    path = os.path.splitext(h5_path)[0] + '.xdmf'
    if not os.path.exists(path):
        check(label + '-xdmf-written', 'no ' + path)
        return
    h5 = h5py.File(h5_path, 'r')
    times = list(h5['time'][:])
    reader, steps = read_xdmf(path)
    problem = '' if steps == times else 'time steps %s, HDF5 /time %s' % (steps, times)
    if records is not None and len(times) != records:
        problem = '%d records, expected %d' % (len(times), records)
    check(label + '-xdmf-every-time-step', problem)
    problems = []
    for k in sorted({1, len(times) - 1}):
        blocks = xdmf_blocks(reader, times[k])
        if sorted(blocks) != sorted(h5['flexible']):
            problems.append('blocks %s' % sorted(blocks))
            break
        for name, grid in blocks.items():
            g = h5['flexible'][name]
            conn = g['connectivity'][:]
            cells = vtk.vtkIdList()
            grid.GetCellPoints(len(conn) - 1, cells)
            got_cell = [cells.GetId(i) for i in range(cells.GetNumberOfIds())]
            celltype = {8: vtk.VTK_HEXAHEDRON, 27: vtk.VTK_TRIQUADRATIC_HEXAHEDRON}[conn.shape[1]]
            if grid.GetNumberOfPoints() != len(g['reference_nodes']) or \
                    grid.GetNumberOfCells() != len(conn) or grid.GetCellType(0) != celltype:
                problems.append('%s: %d points, %d cells of type %d' % (
                    name, grid.GetNumberOfPoints(), grid.GetNumberOfCells(),
                    grid.GetCellType(0)))
                continue
            if got_cell != list(conn[-1] - 1):
                problems.append('%s: last cell %s' % (name, got_cell))
            point, cell = arrays(grid.GetPointData()), arrays(grid.GetCellData())
            for what, got, want in [
                    ('points', vtk_to_numpy(grid.GetPoints().GetData()), g['reference_nodes'][:]),
                    ('displacement', point.get('displacement'), g['displacement'][k]),
                    ('velocity', point.get('velocity'), g['velocity'][k]),
                    ('stress', cell.get('stress'), tensor(g['stress'][k])),
                    ('von_mises', cell.get('von_mises'), g['von_mises'][k])]:
                bad = 'missing' if got is None else differ(got, want, True)
                if bad:
                    problems.append('%s at record %d: %s: %s' % (name, k, what, bad))
    check(label + '-xdmf-values-are-hdf5', '; '.join(problems[:3]))


def check_hex27_order(h5_path, label):
    """A hex27 box element's nodes where VTK's triquadratic hexahedron has
    them (its parametric coordinates): flexmbs's node order is VTK's."""
    g = h5py.File(h5_path, 'r')['flexible']
    body = g[list(g)[0]]
    x = body['reference_nodes'][:][body['connectivity'][0] - 1]
    low, high = x.min(axis=0), x.max(axis=0)
    cell = vtk.vtkTriQuadraticHexahedron()
    pcoords = np.array([cell.GetParametricCoords()[i] for i in range(81)]).reshape(27, 3)
    check(label + '-hex27-node-order-is-vtk', differ((x - low) / (high - low), pcoords, False))


def main():
    exe = executable()
    if not exe or not os.access(exe, os.X_OK):
        check('executable', 'no executable (got %r)' % exe)
        print('%d passed, %d failed' % (passed, failed))
        return 1
    work = tempfile.mkdtemp(prefix='flexmbs-vtk.')
    os.chdir(work)

    # the five-body mechanism: every kind of file (mesh, bodies with chain
    # links, joints), binary and as text
    short = [(r't_end\s*=\s*1\.0', 't_end = 0.01'), (r'n_output\s*=\s*101', 'n_output = 3')]
    for label, form in [('five-body', ''), ('five-body-ascii', ", vtk_format = 'ascii'")]:
        scene = label + '.nml'
        variant('five_body.nml', scene, short,
                "vtk = '%s'%s, file = '%s.h5'" % (label, form, label))
        problem = run(exe, scene)
        check(label + '-run', problem)
        if problem:
            continue
        parts = check_vtu_files(exe, label, label + '.pvd', label + '.h5',
                                exact=not form)
        check(label + '-all-parts', '' if parts == {0, 1, 2} else 'parts %s' % parts)
        check_xdmf(label, label + '.h5')
    with open('five-body_0001.vtu', 'rb') as f:
        head = f.read(400)
    check('five-body-binary-by-default',
          '' if b'format="appended"' in head and b'header_type="UInt64"' in head
          else head.decode(errors='replace'))

    # a modal coupler: the mesh reconstructed from the frame and the modes,
    # drawn and stored alike
    variant('five_body_modal.nml', 'modal.nml', short, "vtk = 'modal', file = 'modal.h5'")
    problem = run(exe, 'modal.nml')
    check('modal-run', problem)
    if not problem:
        parts = check_vtu_files(exe, 'modal', 'modal.pvd', 'modal.h5')
        check('modal-all-parts', '' if parts == {0, 1, 2} else 'parts %s' % parts)
        check_xdmf('modal', 'modal.h5')

    # two flexible bodies: two pieces, two grids per time step
    variant('two_soft_links.nml', 'links.nml',
            [(r't_end\s*=\s*0\.2', 't_end = 0.02'), (r'n_output\s*=\s*21', 'n_output = 3')],
            "vtk = 'links', file = 'links.h5'")
    problem = run(exe, 'links.nml')
    check('two-links-run', problem)
    if not problem:
        check_vtu_files(exe, 'two-links', 'links.pvd', 'links.h5')
        check_xdmf('two-links', 'links.h5')

    # a flexible body alone, hex27, a name with XML's special characters
    variant('flexible_cantilever.nml', 'beam.nml',
            [(r"element\s*=\s*'hex8'", "element = 'hex27', name = 'beam <1> & co'"),
             (r'divisions\s*=\s*8, 1, 1', 'divisions = 2, 1, 1'),
             (r't_end\s*=\s*0\.2', 't_end = 0.01'), (r'n_output\s*=\s*41', 'n_output = 3')],
            "vtk = 'beam', file = 'beam.h5'")
    problem = run(exe, 'beam.nml')
    check('hex27-run', problem)
    if not problem:
        check_vtu_files(exe, 'hex27', 'beam.pvd', 'beam.h5')
        check_xdmf('hex27', 'beam.h5')
        check_hex27_order('beam.h5', 'hex27')

    # rigid bodies only: bodies and joints, no mesh and no XDMF file
    variant('four_bar_chain.nml', 'chain.nml',
            [(r't_end\s*=\s*1\.0', 't_end = 0.02'), (r'n_output\s*=\s*101', 'n_output = 2')],
            "vtk = 'chain', file = 'chain.h5'")
    problem = run(exe, 'chain.nml')
    check('rigid-run', problem)
    if not problem:
        parts = check_vtu_files(exe, 'rigid', 'chain.pvd', 'chain.h5')
        check('rigid-no-mesh-no-xdmf', '' if parts == {1, 2} and not os.path.exists('chain.xdmf')
              else 'parts %s, %s' % (parts, glob.glob('chain*')))

    # a run that fails (the solver's step limit): the XDMF file has the
    # records written before, and the HDF5 file is its data
    variant('flexible_cantilever.nml', 'fails.nml',
            [(r't_end\s*=\s*0\.2', 't_end = 0.2'), (r'n_output\s*=\s*41', 'n_output = 201'),
             (r'^&solver', '&solver max_steps = 12,')],
            "file = 'fails.h5'")
    problem = run(exe, 'fails.nml', code=3)
    check('failed-run', problem)
    if not problem:
        records = len(h5py.File('fails.h5', 'r')['time'])
        check('failed-run-some-records', '' if 1 < records < 201 else '%d records' % records)
        check_xdmf('failed-run', 'fails.h5', records)

    print('%d passed, %d failed' % (passed, failed))
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
