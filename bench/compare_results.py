#!/usr/bin/env python3
"""Compare two folders of flexmbs runs for bit-identity (a refactoring's check).

    /usr/bin/python3 bench/compare_results.py BEFORE_DIR AFTER_DIR [--verbose]
        [--ignore-input]

Each folder holds the runs of the same scenes by two flexmbs executables
(e.g. `flexmbs run NAME.nml --quiet > NAME.out 2> NAME.err; echo $? >
NAME.rc`, the scene's `&output file = 'NAME.h5'`): for every NAME the
files NAME.h5, NAME.out, NAME.err and NAME.rc are compared where either
folder has them.

- NAME.h5: the same groups and datasets, every dataset's values equal bit
  for bit (numpy.array_equal with NaN equal to NaN, same dtype and shape),
  and the same attributes on the file, every group and every dataset, but
  for the timing and the time stamps (CPU, WALL, created and any attribute
  whose name says cpu, wall, time stamp or date).
- NAME.out, NAME.err: the same text but for the timing (CPU=..., WALL=...
  on the counter line, and lines that give seconds of CPU or wall time).
- NAME.rc: the same exit status.

--ignore-input leaves out the attribute input_text (the scene's text), for
runs of scenes that differ by a setting meant to change nothing (such as
newton_system = 'full' against a version without that setting).

The counters (NST, NAC, NRJ and its causes, NFE, NFE_JAC, NJE, NDEC, NSOL,
NPRJ) are the file's attributes and the counter line of NAME.out, so they
are compared exactly. Prints one line per run that differs and a summary
`N runs compared, M identical, K differ`; exits non-zero when any differs
or a run is missing from one folder. Needs h5py and numpy (Debian's
python3-h5py: use /usr/bin/python3 when another python3 comes first).
"""
import os
import re
import sys

import h5py
import numpy as np

TIMING_ATTRIBUTES = re.compile(r'^(cpu|wall|created|date|time_?stamp|.*_time_?stamp)$',
                               re.IGNORECASE)
TIMING_TEXT = re.compile(r'\b(CPU|WALL)=[-+.0-9eE]+')
TIMING_LINE = re.compile(r'(cpu|wall)[ -]?(time|clock)|\bseconds?\b', re.IGNORECASE)


def equal_values(a, b):
    """Bit-identical arrays or scalars (NaN equal to NaN of the same bits)."""
    a = np.asarray(a)
    b = np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.kind in 'fc':
        # the bytes: tells -0.0 from 0.0 and compares NaN payloads too
        return a.tobytes() == b.tobytes()
    if a.dtype.kind == 'O':
        return all(equal_values(x, y) for x, y in zip(a.ravel(), b.ravel()))
    return np.array_equal(a, b)


def compare_attributes(where, x, y, problems):
    keys_x = {k for k in x.attrs if not TIMING_ATTRIBUTES.match(k)}
    keys_y = {k for k in y.attrs if not TIMING_ATTRIBUTES.match(k)}
    for k in sorted(keys_x ^ keys_y):
        problems.append('%s: attribute %s in one file only' % (where, k))
    for k in sorted(keys_x & keys_y):
        if not equal_values(x.attrs[k], y.attrs[k]):
            problems.append('%s: attribute %s: %r != %r'
                            % (where, k, x.attrs[k], y.attrs[k]))


def compare_h5(path_a, path_b):
    problems = []
    datasets = 0
    with h5py.File(path_a, 'r') as fa, h5py.File(path_b, 'r') as fb:
        names_a, names_b = [], []
        fa.visit(names_a.append)
        fb.visit(names_b.append)
        for name in sorted(set(names_a) ^ set(names_b)):
            problems.append('%s in one file only' % name)
        compare_attributes('/', fa, fb, problems)
        for name in sorted(set(names_a) & set(names_b)):
            oa, ob = fa[name], fb[name]
            if isinstance(oa, h5py.Dataset) != isinstance(ob, h5py.Dataset):
                problems.append('%s: a dataset in one file only' % name)
                continue
            compare_attributes(name, oa, ob, problems)
            if isinstance(oa, h5py.Dataset):
                datasets += 1
                if not equal_values(oa[()], ob[()]):
                    problems.append('%s: values differ' % name)
    return problems, datasets


def text_without_timing(path):
    lines = []
    with open(path, encoding='utf-8', errors='replace') as f:
        for line in f:
            line = TIMING_TEXT.sub(r'\1=*', line)
            if TIMING_LINE.search(line) and not line.startswith(('radau5:', 'ddassl:', 'ida:',
                                                                 'mexax:')):
                continue
            lines.append(line)
    return lines


def main(argv):
    global TIMING_ATTRIBUTES
    verbose = '--verbose' in argv
    if '--ignore-input' in argv:
        TIMING_ATTRIBUTES = re.compile(TIMING_ATTRIBUTES.pattern[:-2] + '|input_text)$',
                                       re.IGNORECASE)
    args = [a for a in argv if a not in ('--verbose', '--ignore-input')]
    if len(args) != 2:
        print(__doc__.strip().splitlines()[2].strip())
        return 2
    before, after = args
    runs = set()
    for folder in (before, after):
        for f in os.listdir(folder):
            stem, ext = os.path.splitext(f)
            if ext in ('.h5', '.out', '.err', '.rc'):
                runs.add(stem)
    compared = identical = 0
    datasets = 0
    for run in sorted(runs):
        compared += 1
        problems = []
        for ext in ('.rc', '.out', '.err', '.h5'):
            a = os.path.join(before, run + ext)
            b = os.path.join(after, run + ext)
            if not os.path.exists(a) and not os.path.exists(b):
                continue
            if os.path.exists(a) != os.path.exists(b):
                problems.append('%s%s in one folder only' % (run, ext))
                continue
            if ext == '.h5':
                p, d = compare_h5(a, b)
                problems += p
                datasets += d
            elif text_without_timing(a) != text_without_timing(b):
                problems.append('%s%s differs' % (run, ext))
        if problems:
            print('DIFFER %s: %s' % (run, '; '.join(problems[:6]) +
                                     (' (+%d more)' % (len(problems) - 6)
                                      if len(problems) > 6 else '')))
        else:
            identical += 1
            if verbose:
                print('same %s' % run)
    print('%d runs compared (%d HDF5 datasets), %d identical, %d differ'
          % (compared, datasets, identical, compared - identical))
    return 0 if identical == compared else 1


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
