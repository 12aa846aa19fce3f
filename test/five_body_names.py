#!/usr/bin/env python3
"""The five-body result read as a user reads it: by name, with units, and no
index arithmetic; each value checked against /y, found by its label.

    python3 test/five_body_names.py five_body.h5 [five_body.out]

- the rocker pivot's angle (rad) is the rocker's turn about the world x
  axis, 2 atan2(p1, p0) of its quaternion in /y (the pivot's markers have
  z along x and start aligned);
- coupler node 23's x (m) is its reference position plus its displacement,
  and equals /y's column 'coupler/node 23/x';
- the rocker pivot's reaction force on the rocker (N) is minus the
  joint's first three multipliers in /y (a revolute joint's point
  constraint x_j - x_i = 0 in world coordinates, our sign of lambda), and
  on the ground side (the bearing load) it is minus that, to round-off;
  against lambda to 1e-4 of the largest: the reactions
  come from the multipliers consistent with q and v, which differ from
  the integrator's index-2 ones in /y by about the tolerance (1e-6 here);
- the coupler's von Mises stress per element is that of its Cauchy stress
  (Pa), and with the run's summary (five_body.out) the largest at t_end is
  the one the summary names, in the same element.
Prints `pass`/`FAIL` lines and `N passed, M failed` last.
"""
import re
import sys

import h5py
import numpy as np

passed = failed = 0


def report(name, problem):
    global passed, failed
    if problem:
        failed += 1
        print('FAIL five_body_names/%s: %s' % (name, problem))
    else:
        passed += 1
        print('pass five_body_names/%s' % name)


def text(value):
    return value.decode() if isinstance(value, bytes) else value


with h5py.File(sys.argv[1], 'r') as f:
    labels = [text(s) for s in f['y_labels'][:]]
    units = [text(s) for s in f['y_units'][:]]
    y = f['y'][:]

    def column(label):
        return y[:, labels.index(label)], units[labels.index(label)]

    angle = f['joints/rocker pivot/angle']
    p0, _ = column('rocker/orientation/p0')
    p1, _ = column('rocker/orientation/p1')
    turn = 2.0 * np.arctan2(p1, p0)
    report('rocker-pivot-angle',
           None if text(angle.attrs['unit']) == 'rad'
           and np.abs(angle[:, 0] - turn).max() < 1e-12
           and np.abs(turn).max() > 1e-5 else
           'angle %s %s against %s' % (angle[-1], text(angle.attrs['unit']), turn[-1]))

    node = 23
    reference = f['flexible/coupler/reference_nodes']
    displacement = f['flexible/coupler/displacement']
    x = reference[node - 1, 0] + displacement[:, node - 1, 0]
    x_y, unit = column('coupler/node %d/x' % node)
    report('coupler-node-x',
           None if text(reference.attrs['unit']) == 'm' == text(displacement.attrs['unit'])
           and unit == 'm' and np.abs(x - x_y).max() < 1e-15
           and np.abs(displacement[:, node - 1, 0]).max() > 0 else
           'x %s against /y %s' % (x[-1], x_y[-1]))

    force = f['joints/rocker pivot/reaction_force_j']
    ground = f['joints/rocker pivot/reaction_force']
    lam = np.array([column('joints/rocker pivot/lambda %d' % k)[0] for k in (1, 2, 3)]).T
    report('rocker-pivot-reaction',
           None if text(force.attrs['unit']) == 'N'
           and column('joints/rocker pivot/lambda 1')[1] == 'N'
           and np.abs(force[:] + lam).max() < 1e-4 * max(1.0, np.abs(lam).max())
           and np.abs(ground[:] + force[:]).max() <= 1e-12 * np.abs(force[:]).max()
           and np.abs(lam).max() > 0.1 else
           'force %s against -lambda %s, on the ground %s' % (force[-1], -lam[-1],
                                                             ground[-1]))
    stress = f['flexible/coupler/stress']
    mises = f['flexible/coupler/von_mises']
    xx, yy, zz, xy, yz, xz = np.moveaxis(stress[:], 2, 0)
    from_stress = np.sqrt(0.5 * ((xx - yy)**2 + (yy - zz)**2 + (zz - xx)**2)
                          + 3.0 * (xy**2 + yz**2 + xz**2))
    report('coupler-von-mises',
           None if text(stress.attrs['unit']) == 'Pa' == text(mises.attrs['unit'])
           and mises.shape == from_stress.shape
           and np.abs(mises[:] - from_stress).max() <= 1e-12 * np.abs(from_stress).max()
           and np.abs(from_stress).max() > 0 else
           'von Mises %s against %s' % (mises[-1], from_stress[-1]))
    if len(sys.argv) > 2:
        summary = open(sys.argv[2]).read()
        m = re.search(r'coupler: .*largest von Mises stress (\S+) Pa \(element (\d+)\)', summary)
        last = mises[-1]
        report('coupler-von-mises-as-summary',
               None if m and abs(float(m.group(1)) - last.max()) <= 1e-6 * last.max()
               and int(m.group(2)) == int(np.argmax(last)) + 1 else
               'summary %s against %s in element %d'
               % (m.group(0) if m else '(no line)', last.max(), np.argmax(last) + 1))
print('%d passed, %d failed' % (passed, failed))
sys.exit(1 if failed else 0)
