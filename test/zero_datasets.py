#!/usr/bin/env python3
"""No silent zeros: every real dataset of a result that is zero at every
record must be zero by physics, each such case with its reason below; any
other identically zero dataset is a failure (a quantity that cannot be
computed is left out of the file with a note, never written as zeros).

    python3 test/zero_datasets.py RESULT.h5 [RESULT.h5 ...]

Prints `pass zero_datasets/<file>` or `FAIL zero_datasets/<file>: ...` per
file; exit status 1 on a failure. A reason need not match: round-off can
leave a physically zero series at 1e-18 instead of 0.
"""
import os
import re
import sys

import h5py
import numpy as np

# (scene file name pattern, dataset path pattern, why it is zero)
REASONS = [
    (r'.*', r'joints/[^/]* \(node \d+\)/reaction_torque(_j)?',
     "an 'attach' joint on a node marker pins one node, a point without "
     "rotational freedom: the joint acts through the point and its torque "
     "about the marker vanishes on the node's side (and on both when the "
     "markers coincide)"),
    (r'five_body.*', r'joints/crank pin/reaction_torque(_j)?',
     'a spherical joint transmits no torque about its point (markers coincide)'),
    (r'four_bar.*', r'joints/crank pin/reaction_torque(_j)?',
     'a spherical joint transmits no torque about its point (markers coincide)'),
    (r'five_body.*', r'drivers/rod/reaction_torque(_j)?',
     "a 'distance' driver constrains the length between its markers: its "
     'reaction is a force along that line, without torque about either marker'),
    (r'four_bar.*', r'drivers/motor/reaction_force(_j)?',
     "an 'angle' driver constrains a relative rotation only: its reaction is "
     'a pure torque'),
    (r'four_bar.*', r'joints/(crank|rocker) pivot/reaction_torque(_j)?',
     'a planar mechanism loaded in its plane: a revolute joint whose axis is '
     'normal to the plane carries no moment about in-plane axes, and none '
     'about its own axis'),
    (r'four_bar.*', r'joints/rocker pin/reaction_torque(_j)?',
     'a universal joint in a planar mechanism loaded in its plane: the one '
     'moment it can carry (about the normal of its two axes) lies in the '
     'plane and is not loaded'),
    (r'planar_slider', r'joints/slider/reaction_torque_j',
     'the puck spins about a principal axis (the normal) and the joint holds '
     'it at its centre of mass: the reaction is the normal force through '
     'marker j, and no torque keeps the spin axis'),
    (r'bushing_mount', r'forces/shaker/torque_i',
     "the shaker is an 'applied' point force: no torque on its marker"),
    (r'arm_with_pad', r'chains/base/velocity',
     'the base turns about the vertical axis through its own centre of mass, '
     'which stays at rest'),
]


def scene_name(path):
    return os.path.splitext(os.path.basename(path))[0]


def zero_datasets(path):
    """The real datasets of the file that are zero everywhere."""
    found = []

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and obj.dtype.kind == 'f' and obj.size > 0:
            if not np.any(obj[...]):
                found.append(name)

    with h5py.File(path, 'r') as f:
        f.visititems(visit)
    return found


def reason_for(scene, dataset):
    for k, (scenes, pattern, why) in enumerate(REASONS):
        if re.fullmatch(scenes, scene) and re.fullmatch(pattern, dataset):
            return k, why
    return None, None


def main(paths):
    failed = False
    for path in paths:
        scene = scene_name(path)
        unexplained = [name for name in zero_datasets(path)
                       if reason_for(scene, name)[0] is None]
        if unexplained:
            failed = True
            print(f"FAIL zero_datasets/{scene}: zero at every record without a reason: "
                  + ', '.join(unexplained))
        else:
            print(f"pass zero_datasets/{scene}")
    return 1 if failed else 0


if __name__ == '__main__':
    if len(sys.argv) < 2:
        print(__doc__)
        sys.exit(2)
    sys.exit(main(sys.argv[1:]))
