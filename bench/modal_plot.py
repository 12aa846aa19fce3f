#!/usr/bin/env python3
"""Figures of bench/modal.sh (docs/modal.md).

    python3 bench/modal_plot.py OUT

OUT is build/bench/modal. For each of soft.txt and steel.txt: every run's
error, the largest distance over the records between the coupler's centre
and the reference's (the centre: the mean of the nodes on the mid-plane
y = 0.2 m of the reference mesh, present in both meshes), printed as a
table (OUT/NAME_table.txt) and drawn against the process's CPU
(OUT/work_precision.png). From spin/: the tip's deflection in the plane of
the spin, in the hub's frame (the xmax face's centroid against the xmin
face's, along the hub's y axis), for the modal and the nonlinear beam
(OUT/spin_up.png).
"""
import os
import sys

import h5py
import numpy as np

out = sys.argv[1]


def centre(path):
    """Times and the coupler's mid-plane centre (records, 3)."""
    with h5py.File(path, 'r') as f:
        g = f['flexible/coupler']
        x0 = g['reference_nodes'][:]                  # (nodes, 3)
        u = g['displacement'][:]                      # (records, nodes, 3)
        mid = np.abs(x0[:, 1] - 0.2) < 1e-9
        return f['time'][:], (x0[None, mid, :] + u[:, mid, :]).mean(axis=1)


def table(name):
    """Rows (mesh, model, k, tol, cpu, solver_cpu, nst, error) of NAME.txt."""
    folder = os.path.join(out, name)
    rows = []
    t_ref, c_ref = centre(os.path.join(folder, 'ref.h5'))
    with open(os.path.join(out, name + '.txt')) as f:
        for line in f:
            part = line.split()
            if len(part) != 8 or part[0] not in ('coarse', 'fine'):
                continue
            mesh, model, k, tol, cpu, solver, nst, h5 = part
            path = os.path.join(folder, h5)
            err = float('nan')
            if os.path.exists(path):
                t, c = centre(path)
                if len(t) == len(t_ref):
                    err = float(np.max(np.linalg.norm(c - c_ref, axis=1)))
            rows.append((mesh, model, int(k), float(tol), float(cpu), float(solver),
                         int(nst), err))
    with open(os.path.join(out, name + '_table.txt'), 'w') as f:
        f.write('mesh    model      k    tol    process_cpu_s  solver_cpu_s   NST  '
                'centre_error_m\n')
        for r in rows:
            f.write('%-7s %-9s %3d  %7.0e  %10.3f  %12.3f  %5d  %12.3e\n' % r)
    print(open(os.path.join(out, name + '_table.txt')).read())
    return rows


def work_precision(names):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(names), figsize=(6.5 * len(names), 5))
    axes = np.atleast_1d(axes)
    for ax, (name, rows) in zip(axes, names):
        lines = sorted({(r[0], r[1], r[2]) for r in rows},
                       key=lambda x: (x[0], x[1] != 'nonlinear', x[2]))
        for mesh, model, k in lines:
            pts = sorted((r[7], r[4]) for r in rows if (r[0], r[1], r[2]) == (mesh, model, k)
                         and np.isfinite(r[7]))
            if not pts:
                continue
            label = '%s %s' % (mesh, 'nonlinear' if model == 'nonlinear' else 'modal k=%d' % k)
            style = '-o' if model == 'nonlinear' else ('--s' if mesh == 'fine' else ':^')
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], style, label=label)
        ax.set_xlabel('coupler centre error against the fine nonlinear run [m]')
        ax.set_ylabel('CPU of the whole run [s]')
        ax.set_title('five-body mechanism, %s coupler' % name)
        ax.grid(True, which='both', alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, 'work_precision.png'), dpi=110)


def spin_up():
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True,
                                  gridspec_kw={'height_ratios': [3, 1]})
    for model, style in (('nonlinear', '-'), ('modal', '--')):
        path = os.path.join(out, 'spin', model + '.h5')
        if not os.path.exists(path):
            continue
        with h5py.File(path, 'r') as f:
            t = f['time'][:]
            g = f['flexible/beam']
            x = g['reference_nodes'][:][None, :, :] + g['displacement'][:]
            tip = x[:, g['node_sets/xmax'][:] - 1, :].mean(axis=1)
            root = x[:, g['node_sets/xmin'][:] - 1, :].mean(axis=1)
            p = f['bodies/hub/orientation'][:]
            # the hub's y axis: A(p) e_y, A = (p0² − e·e) I + 2 e eᵀ + 2 p0 [e]×
            e0, e = p[:, 0], p[:, 1:]
            ey = np.stack([2 * e[:, 0] * e[:, 1] - 2 * e0 * e[:, 2],
                           e0**2 - (e**2).sum(axis=1) + 2 * e[:, 1]**2,
                           2 * e[:, 1] * e[:, 2] + 2 * e0 * e[:, 0]], axis=1)
            dev = ((tip - root) * ey).sum(axis=1)
            ok = np.isfinite(dev)
            ax.plot(t[ok], 1000 * dev[ok], style, label='%s beam' % model)
            w = f['bodies/hub/angular_velocity'][:][:, 2]
            if model == 'nonlinear':
                ax2.plot(t, np.abs(w), 'k-')
    ax.set_ylabel('tip deflection in the spin plane [mm]')
    ax.set_yscale('symlog', linthresh=1.0)
    ax.grid(True, alpha=0.3)
    ax.legend()
    ax.set_title('spin-up of a beam (hex8 10x1x1, clamped omega_1 = 2.30 rad/s)')
    ax2.axhline(2.30, color='gray', lw=0.8, ls=':')
    ax2.set_ylabel('spin [rad/s]')
    ax2.set_xlabel('t [s]')
    ax2.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out, 'spin_up.png'), dpi=110)


names = [(n, table(n)) for n in ('soft', 'steel') if os.path.exists(os.path.join(out, n + '.txt'))]
if names:
    work_precision(names)
if os.path.isdir(os.path.join(out, 'spin')):
    spin_up()
