#!/usr/bin/env python3
"""The named part of a multibody result (run/named_output) against /y.

    python3 test/result_names.py RESULT.h5 [FLEXMBS]

Every series under /bodies, /joints and /drivers has a `unit` and one row
per record of /time. Each body's position and orientation are the
7 coordinates (r, p) of one body in /q, its velocity and body-fixed angular
velocity the matching 6 of /v (found, not assumed); the rotation matrix is
that of the quaternion and orthogonal (up to |p|^2); the world angular velocity is
R ω'; every joint's and driver's reaction force and torque on the body of
marker i are among the per-joint columns of /reactions; each flexible
body's reference nodes plus displacements, over the nodes that move, are
one slice of /q, its node velocities one of /v (a modal body's
modal_coordinates are one slice of /q instead, its frequencies positive and
ascending). With FLEXMBS, `flexmbs
columns` by name (BODY/position/z, JOINT/reaction_force/x, BODY/node N/x
and .../velocity/y) prints the same numbers as the datasets. Chain links:
coordinate and rate are slices of /q and /v, the rotation orthonormal, and
velocity and angular velocity the time derivatives (central differences)
of position and rotation. A revolute joint's angle changes as the body it
holds to the ground turns. Prints `pass` or
`FAIL` lines and `N passed, M failed` last.
"""
import sys

import h5py
import numpy as np

passed = failed = 0


def report(name, problem):
    global passed, failed
    if problem:
        failed += 1
        print('FAIL result_names/%s: %s' % (name, problem))
    else:
        passed += 1
        print('pass result_names/%s' % name)


def rotation(p):
    p0, e = p[0], p[1:]
    skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    return (p0 * p0 - e @ e) * np.eye(3) + 2 * np.outer(e, e) + 2 * p0 * skew


f = h5py.File(sys.argv[1], 'r')
name = sys.argv[1].rsplit('/', 1)[-1]
if f.attrs.get('problem') not in ('multibody', 'flexible_body', 'rigid_chain'):
    print('result_names: %s has no bodies: nothing named to check' % name)
    print('0 passed, 0 failed')
    sys.exit(0)
records = len(f['time'])
q, v = f['q'][:], f['v'][:]
problems = []


def series(group):
    out = []
    if group in f:
        f[group].visititems(lambda n, o: out.append(group + '/' + n)
                            if isinstance(o, h5py.Dataset) else None)
    return out


for path in series('bodies') + series('joints') + series('drivers') + series('chains') + \
        [p for p in series('flexible') if p.endswith(('/displacement', '/velocity'))]:
    d = f[path]
    if not isinstance(d.attrs.get('unit'), str):
        problems.append('%s has no unit (a UTF-8 string)' % path)
    if d.shape[0] != records:
        problems.append('%s has %d records, /time %d' % (path, d.shape[0], records))
report(name + '/units-and-records', '; '.join(problems[:5]))

bodies = sorted(f['bodies']) if 'bodies' in f else []
problems = []
for body in bodies:
    g = f['bodies'][body]
    pose = np.hstack([g['position'][:], g['orientation'][:]])
    at = [k for k in range(0, q.shape[1] - 6, 7) if np.array_equal(q[:, k:k + 7], pose)]
    if len(at) != 1:
        problems.append('%s: (position, orientation) is not one body of /q' % body)
        continue
    i = at[0] // 7
    vel = np.hstack([g['velocity'][:], np.zeros((records, 3))])
    omega_body = v[:, 6 * i + 3:6 * i + 6]
    if not np.array_equal(v[:, 6 * i:6 * i + 3], g['velocity'][:]):
        problems.append('%s: velocity is not /v of body %d' % (body, i + 1))
    for k in range(records):
        r = rotation(pose[k, 3:])
        stored = g['rotation_matrix'][k].reshape(3, 3, order='F')
        # R of a quaternion p is |p|^2 times a rotation (|p| drifts with the
        # tolerance unless the run projects)
        norm2 = pose[k, 3:] @ pose[k, 3:]
        if np.max(np.abs(stored - r)) > 1e-12 or \
                np.max(np.abs(r.T @ r - norm2 ** 2 * np.eye(3))) > 1e-12:
            problems.append('%s: rotation_matrix at record %d' % (body, k))
            break
        if np.max(np.abs(g['angular_velocity'][k] - r @ omega_body[k])) > \
                1e-12 * (1 + np.max(np.abs(omega_body[k]))):
            problems.append('%s: angular_velocity at record %d is not R w\'' % (body, k))
            break
report(name + '/bodies-match-y (%d bodies)' % len(bodies), '; '.join(problems[:5]))

problems = []
joints = [p.rsplit('/', 1)[0] for p in series('joints') + series('drivers')
          if p.endswith('/reaction_force')]
if joints:
    reactions = f['reactions'][:]
    columns = [reactions[:, c:c + 6] for c in range(0, reactions.shape[1], 12)]
    for joint in joints:
        mine = np.hstack([f[joint + '/reaction_force'][:], f[joint + '/reaction_torque'][:]])
        scale = 1 + np.max(np.abs(mine))
        if not any(np.max(np.abs(c - mine)) <= 1e-9 * scale for c in columns):
            problems.append('%s: reaction not among /reactions' % joint)
report(name + '/reactions-match (%d joints and drivers)' % len(joints), '; '.join(problems[:5]))

problems = []
flexible = sorted(f['flexible']) if 'flexible' in f else []
for body in flexible:
    g = f['flexible'][body]
    x0 = g['reference_nodes'][:]                      # (nodes, 3)
    u = g['displacement'][:]                          # (records, nodes, 3)
    if u.shape[1:] != x0.shape or g['velocity'].shape != u.shape:
        problems.append('%s: shapes %s, %s' % (body, x0.shape, u.shape))
        continue
    conn = g['connectivity'][:]
    if conn.min() < 1 or conn.max() > x0.shape[0]:
        problems.append('%s: connectivity outside nodes 1..%d' % (body, x0.shape[0]))
    if 'frequencies' in g:
        # a modal body: its nodes are reconstructed from the frame and η;
        # η is one slice of /q, the frequencies positive and ascending
        omega = g['frequencies'][:]
        if np.any(omega <= 0) or np.any(np.diff(omega) < 0):
            problems.append('%s: frequencies not positive and ascending' % body)
        if 'modal_coordinates' in g:
            eta = g['modal_coordinates'][:].reshape(records, -1)
            m = eta.shape[1]
            if not any(np.array_equal(q[:, k:k + m], eta) for k in range(q.shape[1] - m + 1)):
                problems.append('%s: modal_coordinates are not one slice of /q' % body)
        if not (np.all(np.isfinite(u)) and np.all(np.isfinite(g['velocity'][:]))):
            problems.append('%s: reconstructed nodes not finite' % body)
        continue
    # the free coordinates, node by node, are one slice of /q (fixed nodes
    # do not move: displacement 0)
    moving = np.any(u != 0, axis=0).reshape(-1)
    x = (x0[None, :, :] + u).reshape(records, -1)[:, moving]
    m = x.shape[1]
    at = [k for k in range(q.shape[1] - m + 1) if np.array_equal(q[:, k:k + m], x)]
    if len(at) != 1:
        problems.append('%s: the moving nodes\' positions are not one slice of /q' % body)
        continue
    vel = g['velocity'][:].reshape(records, -1)[:, moving]
    if not any(np.array_equal(v[:, k:k + m], vel) for k in range(v.shape[1] - m + 1)):
        problems.append('%s: the nodes\' velocities are not one slice of /v' % body)
report(name + '/flexible-match-y (%d bodies)' % len(flexible), '; '.join(problems[:5]))

problems = []
links = sorted(f['chains']) if 'chains' in f else []
t = f['time'][:]
for link in links:
    g = f['chains'][link]
    coordinate, rate = g['coordinate'][:], g['rate'][:]
    m, n = coordinate.shape[1], rate.shape[1]
    if not any(np.array_equal(q[:, k:k + m], coordinate) for k in range(q.shape[1] - m + 1)):
        problems.append('%s: coordinate is not a slice of /q' % link)
    if not any(np.array_equal(v[:, k:k + n], rate) for k in range(v.shape[1] - n + 1)):
        problems.append('%s: rate is not a slice of /v' % link)
    r = g['rotation_matrix'][:].reshape(records, 3, 3, order='F')
    if np.max(np.abs(np.einsum('kij,kil->kjl', r, r) - np.eye(3))) > 1e-12:
        problems.append('%s: rotation_matrix not orthonormal' % link)
    # the velocities are the time derivatives of the position and of R:
    # central differences over the output times, second order accurate
    x, vel, w = g['position'][:], g['velocity'][:], g['angular_velocity'][:]
    dt = t[2:] - t[:-2]
    dx = (x[2:] - x[:-2]) / dt[:, None]
    dr = (r[2:] - r[:-2]) / dt[:, None, None]
    w_skew = np.einsum('kij,klj->kil', dr, r[1:-1])          # dR R^T = [w]x
    w_fd = np.stack([w_skew[:, 2, 1], w_skew[:, 0, 2], w_skew[:, 1, 0]], axis=1)
    scale_v = 1e-3 + np.max(np.abs(vel))
    scale_w = 1e-3 + np.max(np.abs(w))
    if np.max(np.abs(dx - vel[1:-1])) > 2e-2 * scale_v:
        problems.append('%s: velocity is not dx/dt (%.2e)' % (link, np.max(np.abs(dx - vel[1:-1]))))
    if np.max(np.abs(w_fd - w[1:-1])) > 2e-2 * scale_w:
        problems.append('%s: angular_velocity is not from dR/dt (%.2e)'
                        % (link, np.max(np.abs(w_fd - w[1:-1]))))
report(name + '/chains-consistent (%d links)' % len(links), '; '.join(problems[:5]))

problems = []
if 'monitor' in f:
    if 'energy' not in f or not np.array_equal(f['energy'][:], f['monitor'][:, 3]) or \
            f['energy'].attrs.get('unit') != 'J':
        problems.append('/energy is not the monitor\'s energy in J')
    if 'drift_note' in f.attrs:
        # no constraints: no /drift, the note says so, the monitor's columns are 0
        if 'drift' in f or np.any(f['monitor'][:, 1:3]) or \
                'no constraints' not in str(f.attrs['drift_note']):
            problems.append('/drift left out, but the scene has constraints or no note')
    elif 'drift' not in f or not np.array_equal(f['drift'][:], f['monitor'][:, 1:3]):
        problems.append('/drift is not the monitor\'s drift')
report(name + '/energy-and-drift', '; '.join(problems))

# /y_labels and /y_units: every component named once, with a unit; the
# labelled columns of /y are the named series
problems = []
labels = [x.decode() if isinstance(x, bytes) else x for x in f['y_labels'][:]]
units = [x.decode() if isinstance(x, bytes) else x for x in f['y_units'][:]]
y = f['y'][:]
if len(labels) != y.shape[1] or len(units) != y.shape[1]:
    problems.append('%d labels, %d units for %d components' % (len(labels), len(units),
                                                              y.shape[1]))
elif len(set(labels)) != len(labels) or any(not u for u in units):
    problems.append('labels not unique or units missing')
else:
    column = {label: k for k, label in enumerate(labels)}
    for body in bodies:
        for k, axis in enumerate('xyz'):
            at = column.get('%s/position/%s' % (body, axis))
            if at is None or not np.array_equal(y[:, at], f['bodies'][body]['position'][:, k]):
                problems.append('%s/position/%s is not its named column' % (body, axis))
    for body in flexible:
        g = f['flexible'][body]
        for node in (1, g['reference_nodes'].shape[0]):
            at = column.get('%s/node %d/x' % (body, node))
            if at is not None and np.max(np.abs(y[:, at] - g['reference_nodes'][node - 1, 0]
                                                - g['displacement'][:, node - 1, 0])) > 1e-15:
                problems.append('%s/node %d/x is not reference + displacement' % (body, node))
report(name + '/y-labels-and-units (%d)' % len(labels), '; '.join(problems[:5]))

# a revolute joint's angle: a joint to the ground turns its body by the
# change of the angle (the rotation angle of R(t) R(0)^T, the quaternion's
# drift aside); at least one such joint and body in a file with angles
# and no flexible body
angles = [j for j in joints if j + '/angle' in f]
matched = []
for joint in angles:
    delta = np.abs(f[joint + '/angle'][:, 0] - f[joint + '/angle'][0, 0])
    for body in bodies:
        r = f['bodies'][body]['rotation_matrix'][:].reshape(records, 3, 3, order='F')
        rel = np.einsum('kij,lj->kil', r, r[0])
        turn = np.arccos(np.clip((np.trace(rel, axis1=1, axis2=2) - 1) / 2, -1, 1))
        if np.max(np.abs(turn - delta)) <= 1e-3 * np.max(delta) + 1e-7 and np.max(delta) > 0:
            matched.append(joint)
            break
# (a hinge on a flexible body turns with the body's bending: no check there)
report(name + '/joint-angles (%d of %d turn a body by them)' % (len(matched), len(angles)),
       '' if not angles or matched or flexible else 'no joint angle is the turn of a body')

if len(sys.argv) > 2:
    import subprocess
    names, expected = [], []
    for body in bodies[:2]:
        names.append(body + '/position/z')
        expected.append(f['bodies'][body]['position'][:, 2])
    for joint in joints[:2]:
        names.append(joint.split('/', 1)[1] + '/reaction_force/x')
        expected.append(f[joint + '/reaction_force'][:, 0])
    for link in links[:2]:
        names.append(link + '/coordinate/1')
        expected.append(f['chains'][link]['coordinate'][:, 0])
    for joint in angles[:1]:
        names.append(joint.split('/', 1)[1] + '/angle')
        expected.append(f[joint + '/angle'][:, 0])
    for body in flexible[:1]:
        g = f['flexible'][body]
        n = g['reference_nodes'].shape[0]
        names += ['%s/node %d/x' % (body, n), '%s/node 1/velocity/y' % body]
        expected += [g['reference_nodes'][n - 1, 0] + g['displacement'][:, n - 1, 0],
                     g['velocity'][:, 0, 1]]
    run = subprocess.run([sys.argv[2], 'columns', sys.argv[1]] + names,
                         capture_output=True, text=True)
    problem = ''
    if run.returncode != 0:
        problem = 'exit %d: %s' % (run.returncode, run.stderr.strip())
    else:
        table = np.loadtxt(run.stdout.splitlines(), ndmin=2)
        if table.shape != (records, len(names) + 1):
            problem = 'shape %s' % (table.shape,)
        elif np.max(np.abs(table[:, 0] - f['time'][:])) > 1e-14:
            problem = 'the times differ'
        else:
            for k, (column, want) in enumerate(zip(names, expected)):
                if np.max(np.abs(table[:, k + 1] - want)) > 1e-13 * (1 + np.max(np.abs(want))):
                    problem += '%s differs; ' % column
    report(name + '/columns-by-name (%d)' % len(names), problem)

print('%d passed, %d failed' % (passed, failed))
sys.exit(1 if failed else 0)
