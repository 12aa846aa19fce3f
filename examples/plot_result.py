#!/usr/bin/env python3
"""Plot a result by name.

    python3 examples/plot_result.py RESULT.h5 [QUANTITY ...] [PLOT.png]

Without a QUANTITY: the first rigid body's position, and the node of the
first flexible body that moved most. With quantities, one panel each, named
as the file names them (no index arithmetic), with or without the group
and with an optional component:

    rocker/position            the three components of /bodies/rocker/position
    rocker/position/z          one of them (x, y, z or a number from 1)
    rocker pivot/angle         a joint's angle (/joints/...)
    motor/reaction_torque/z    a driver's reaction (/drivers/...)
    energy                     a root series (/energy, /drift)

Writes PLOT.png (default: RESULT.png).
"""
import sys

import h5py
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
import numpy as np

GROUPS = ['', 'bodies/', 'joints/', 'drivers/', 'forces/', 'chains/', 'flexible/']
COMPONENTS = {'x': 0, 'y': 1, 'z': 2}


def find(f, name):
    """(dataset, column or None, label) of a quantity name; SystemExit when
    the file has no such quantity."""
    for prefix in GROUPS:
        path = prefix + name
        if path in f and isinstance(f[path], h5py.Dataset):
            return f[path], None, name
        head, _, last = path.rpartition('/')
        if head in f and isinstance(f[head], h5py.Dataset):
            column = COMPONENTS.get(last)
            if column is None and last.isdigit():
                column = int(last) - 1
            if column is not None:
                return f[head], column, name
    sys.exit("plot_result.py: no quantity '%s' in %s (try a path of the file, "
             "e.g. 'bodies/<body>/position/z')" % (name, f.filename))


def default_panels(f, axes):
    body = sorted(f['bodies'])[0]
    position = f['bodies'][body]['position']
    for k, axis in enumerate('xyz'):
        axes[0].plot(f['time'][:], position[:, k], label=axis)
    axes[0].set_ylabel('%s position [%s]' % (body, position.attrs['unit']))
    axes[0].legend()
    if 'flexible' in f:
        name = sorted(f['flexible'])[0]
        u = f['flexible'][name]['displacement']
        magnitude = np.linalg.norm(u[:], axis=2)          # (records, nodes)
        node = int(np.argmax(magnitude.max(axis=0)))      # index: node id - 1
        axes[1].plot(f['time'][:], magnitude[:, node])
        axes[1].set_ylabel('%s node %d |u| [%s]' % (name, node + 1, u.attrs['unit']))


def main(argv):
    if len(argv) < 2 or argv[1] in ('-h', '--help'):
        print(__doc__)
        return 0 if len(argv) > 1 else 2
    path = argv[1]
    pngs = [a for a in argv[2:] if a.endswith('.png')]
    names = [a for a in argv[2:] if not a.endswith('.png')]
    png = pngs[0] if pngs else path.rsplit('.', 1)[0] + '.png'
    with h5py.File(path, 'r') as f:
        t = f['time'][:]
        panels = max(len(names), 2)
        fig, axes = plt.subplots(panels, 1, figsize=(7, 3 * panels), sharex=True,
                                 squeeze=False)
        axes = axes[:, 0]
        if not names:
            default_panels(f, axes)
        for ax, name in zip(axes, names):
            data, column, label = find(f, name)
            unit = data.attrs.get('unit', '')
            unit = unit.decode() if isinstance(unit, bytes) else unit
            values = data[...]
            if column is not None:
                ax.plot(t, values[:, column])
            elif values.ndim == 1 or values.shape[1] == 1:
                ax.plot(t, values.reshape(len(t), -1)[:, 0])
            else:
                # a vector per record, or a series per node or element (flattened)
                values = values.reshape(len(t), -1)
                for k in range(values.shape[1]):
                    ax.plot(t, values[:, k], label='xyz'[k] if values.shape[1] == 3 else str(k + 1))
                if values.shape[1] <= 6:
                    ax.legend()
            ax.set_ylabel('%s [%s]' % (label, unit) if unit else label)
        axes[-1].set_xlabel('t [s]')
        fig.tight_layout()
        fig.savefig(png, dpi=80)
    print('plot: %s' % png)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
