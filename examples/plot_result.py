#!/usr/bin/env python3
"""Plot a result by name: a rigid body's motion and a flexible body's node.

    python3 examples/plot_result.py RESULT.h5 [PLOT.png]

Reads the named datasets of a flexmbs result (no index arithmetic): the
first rigid body's position, and the node of the first flexible body that
moved most, with their units; writes a PNG with both.
"""
import sys

import h5py
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
import numpy as np

path = sys.argv[1]
png = sys.argv[2] if len(sys.argv) > 2 else path.rsplit('.', 1)[0] + '.png'
with h5py.File(path, 'r') as f:
    t = f['time'][:]
    body = sorted(f['bodies'])[0]
    position = f['bodies'][body]['position']
    unit = position.attrs['unit']
    xyz = position[:]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for k, axis in enumerate('xyz'):
        top.plot(t, xyz[:, k], label=axis)
    top.set_ylabel('%s position [%s]' % (body, unit))
    top.legend()
    if 'flexible' in f:
        name = sorted(f['flexible'])[0]
        u = f['flexible'][name]['displacement']
        magnitude = np.linalg.norm(u[:], axis=2)          # (records, nodes)
        node = int(np.argmax(magnitude.max(axis=0)))      # index: node id - 1
        bottom.plot(t, magnitude[:, node])
        bottom.set_ylabel('%s node %d |u| [%s]' % (name, node + 1, u.attrs['unit']))
    bottom.set_xlabel('t [s]')
    fig.tight_layout()
    fig.savefig(png, dpi=80)
print('plotted %s: %s and a node of the flexible body' % (png, body))
