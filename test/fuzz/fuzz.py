#!/usr/bin/env python3
"""Fuzzer of the scene input path of `flexmbs run`.

Generates variants of the example scenes (inputs/*.nml, and a small scene
on inputs/meshes/bar_hex8.mesh) by one operator each — deletions,
truncations, byte flips, wrong types, NaN/Inf/huge/negative/zero values,
unknown names and groups, duplicated names and groups, broken references,
hostile paths, oversized counts, other valid choices — and runs each through
the real executable (`flexmbs run VARIANT --quiet`) in a folder of its own,
with the end time, the output count and the step limit cut to a few steps
(after mutating, unless the operator aims at that variable), a time limit
and an address-space limit per case. Case i is made from the seed and i
alone (random.Random), so every case is reproducible on its own.

Asserted for every case:
  no-crash         no signal, no "Fortran runtime error", no backtrace, and an
                   exit code of 0, 2 or 3 (gfortran's runtime errors also exit
                   2, so the code alone proves nothing)
  no-hang          finished within the time limit
  inputs-unchanged the scene, the mesh and every file there before the run
                   (hashed) are as they were
  exit-2-no-output an exit 2 leaves no new file anywhere in the case folder
  exit-2-message   an exit 2 says why, naming the scene file as given, in
                   flexmbs's words (no raw namelist or runtime message)
  own-messages     whatever the exit, every line on standard error is
                   flexmbs's own ('flexmbs: ...'): no compiler or library
                   note (gfortran's floating-point note, HDF5-DIAG, ...)
  valid-output     an exit 0 or 3 leaves a readable HDF5 file where the
                   variant says (h5py when importable, else its signature)
  invalid-refused  a variant that the operator makes invalid (an unknown
                   name, a wrong type, a broken reference, ...) exits 2
And over all cases:
  stages           every validation stage of the input path was reached by
                   some exit 2, and every exit-2 message is assigned a stage
                   by the patterns in STAGES
  tally            every invalid variant exited 2, every valid one 0 or 3, and
                   the counts add up (invalid: made so by the operator, or
                   refused; valid: the rest)

Output: one line per failed case (`FAIL case 123 ...`), the tally
    fuzz: N cases (k invalid: k exit 2; m valid: exit 0/3), 0 crashes,
          0 hangs, 0 outputs after exit 2, 0 inputs changed
(one line), a line per operator and per stage, `pass fuzz/NAME` or
`FAIL fuzz/NAME: ...` per property above, and last `N passed, M failed`.
Exit status 1 when any property failed.

Usage:
    python3 test/fuzz/fuzz.py [--exe PATH] [--cases N] [--seed S] [--jobs J]
    python3 test/fuzz/fuzz.py --case 123 --keep    # one case; keep its folder
    python3 test/fuzz/fuzz.py --case 123 --show    # print its files, run nothing
Without --exe the debug build is used (found through fpm, as test/cli.sh
does); h5py comes with Debian's python3-h5py (test/fuzz/run.sh picks the
python3 that has it). Defects found so far: test/fuzz/KNOWN.md. Saved
reproducers in test/fuzz/cases/ (NAME.nml, optional NAME.mesh for its
'bar.mesh'; a first line `! expect: exit 2` or `! expect: run`) run after
the generated cases, as cases 'cases/NAME'.
"""

import argparse
import hashlib
import os
import random
import re
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

try:
    import h5py
except ImportError:  # the Makefile installs python3-h5py; the signature suffices
    h5py = None

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
INPUTS = os.path.join(ROOT, 'inputs')
SAVED = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'cases')

DEFAULT_CASES = 1000
DEFAULT_SEED = 16
# s per case: a variant takes ~0.1 s, one on the fine coupler mesh up to ~6 s
# on a busy machine; its seed gets the longer limit
TIME_LIMIT, TIME_LIMIT_FINE = 10.0, 30.0
ADDRESS_LIMIT = 6 << 30      # bytes of address space per case: a run takes ~0.5 GB
END_TIME_STEP = 1.0e-4       # s: t_end = t_start + this (a few steps)
MAX_STEPS = 100              # step limit of every variant that does not aim at it
HDF5_SIGNATURE = b'\x89HDF\r\n\x1a\n'

# What a crash leaves in the output (gfortran, glibc, the shell).
CRASH_PATTERNS = re.compile(
    r'Fortran runtime error|Backtrace for this error|Program received signal|'
    r'Error termination|ERROR STOP|Segmentation fault|Aborted|core dumped|'
    r'Operating system error|Allocation would exceed memory limit|'
    r'malloc\(\)|free\(\)|double free|stack smashing|#\d+\s+0x[0-9a-f]+')
# Raw messages of the compiler's namelist reader or runtime, which name
# neither the variable nor the value (DESIGN: validation comes first).
RAW_MESSAGE = re.compile(
    r'Cannot match namelist|namelist read|Bad (real|integer|logical|value|repeat)|'
    r'End of file|Internal unit|Cannot open file|Invalid string input|HDF5-DIAG')

# The validation stages of the input path, in the order a scene meets them,
# each with the patterns of its exit-2 messages (searched in the message
# after 'flexmbs: '); the first stage that matches takes the message.
STAGES = [
    ('file', [r"^[^&]*?: (no such file|is a folder, not a file|not a regular file|"
              r"cannot (open|read|hold))"]),
    ('mesh', [r"mesh_file = '[^']*': ", r"the mesh file '[^']*' has"]),
    ('output path', [r"&output: (file|vtk|table)( = '.*')?: .*(would overwrite|the scene file "
                     r"itself|is the mesh file|does not exist|is not a folder|is a folder|"
                     r"not a regular file|has no bodies to draw|must end in)"]),
    ('lexer', [r"unexpected text", r"not closed by", r"expected '=' after",
               r"has no value", r"unterminated string", r": unexpected '",
               r": needs \d+ values", r": at most \d+ values"]),
    ('types', [r"must be a quoted string", r"must be a real number", r"must be an integer",
               r"must be \.true\. or \.false\.", r"out of the range of",
               r"longer than \d+ characters"]),
    ('names', [r"unknown group", r"unknown variable", r"given more than once",
               r"belongs in a study file"]),
    ('solver options', [r"&solver: (options|linear solver|radau5|ddassl|ida|mexax): ",
                        r"&solver: (linear_solver|sparse_ordering) = '[^']*'(:| needs)"]),
    ('ranges', [r"&(simulation|solver|output): [a-z_0-9]+( = .*| \(default\))?: "]),
    ('references', [r"no &marker of that name", r"no &rigid_body or &rigid_chain body",
                    r"must be 'ground' or a body of an earlier", r"no such node set",
                    r"no node set named", r"no such element set", r"no element set named"]),
    ('semantics', [r"&(flexible_body|material|multibody|rigid_body|marker|joint|driver|"
                   r"force|rigid_chain)\b", r"problem = '[a-z_0-9]*': needs",
                   r"constraint set is redundant"]),
    ('run', [r"no consistent initial state", r"no initial y'"]),
]


# ----------------------------------------------------------------------
# The schema and the scene text
# ----------------------------------------------------------------------

def read_schema():
    """{(group, name): (kind, count)} from the var_spec_t table of the sources."""
    schema = {}
    # the count is the fourth argument when given by position (not name=)
    spec = re.compile(r"var_spec_t\('(\w+)',\s*'(\w+)',\s*kind_(\w+)(?:,\s*(\w+)\b(?!\s*=))?")
    for folder, _, files in os.walk(os.path.join(ROOT, 'src')):
        for name in sorted(files):
            if not name.endswith(('.f90', '.F90')):
                continue
            with open(os.path.join(folder, name), encoding='utf-8', errors='replace') as f:
                for m in spec.finditer(f.read()):
                    count = m.group(4)
                    count = int(count) if count and count.isdigit() else (3 if count else 1)
                    schema[(m.group(1), m.group(2))] = (m.group(3), count)
    if not schema:
        raise SystemExit('fuzz: no var_spec_t schema found under src/')
    return schema


@dataclass
class Assign:
    name: str
    start: int            # of the name
    eq: int               # of '='
    items: list           # [(start, end)] of each value
    end: int              # after the last value

@dataclass
class Group:
    name: str
    start: int            # of '&'
    end: int              # after '/'
    assigns: list = field(default_factory=list)


def parse(text):
    """Groups and assignments of a (valid) scene text, with their spans."""
    groups, i, n = [], 0, len(text)

    def skip(i, newlines=True):
        while i < n:
            c = text[i]
            if c == '!':
                while i < n and text[i] != '\n':
                    i += 1
            elif c in ' \t\r' or (newlines and c == '\n'):
                i += 1
            else:
                break
        return i

    def value_end(i):
        if text[i] in '\'"':
            q, i = text[i], i + 1
            while i < n and text[i] != '\n':
                if text[i] == q:
                    if i + 1 < n and text[i + 1] == q:
                        i += 2
                        continue
                    return i + 1
                i += 1
            raise ValueError('unterminated string')
        while i < n and text[i] not in ' \t\r\n,/!':
            i += 1
        return i

    name_re = re.compile(r'[A-Za-z][A-Za-z0-9_]*')
    while True:
        i = skip(i)
        if i >= n:
            return groups
        if text[i] != '&':
            raise ValueError('text outside a group at %d' % i)
        m = name_re.match(text, i + 1)
        g = Group(m.group(0).lower(), i, -1)
        i = m.end()
        while True:
            i = skip(i)
            if text[i] == '/':
                g.end = i + 1
                i += 1
                break
            if text[i] == ',':
                i += 1
                continue
            m = name_re.match(text, i)
            if not m:
                raise ValueError('bad name at %d' % i)
            a = Assign(m.group(0).lower(), i, -1, [], -1)
            i = skip(m.end())
            a.eq = i
            i = skip(i + 1)
            while True:
                e = value_end(i)
                a.items.append((i, e))
                i = e
                j = skip(i)
                if j < n and text[j] == ',':
                    k = skip(j + 1)
                    nm = name_re.match(text, k)
                    if nm and skip(nm.end()) < n and text[skip(nm.end())] == '=':
                        break
                    if k < n and text[k] in '/&':
                        break
                    i = k
                    continue
                break
            a.end = a.items[-1][1]
            g.assigns.append(a)
        groups.append(g)


def replace(text, start, end, new):
    return text[:start] + new + text[end:]


@dataclass
class Seed:
    name: str
    text: str
    mesh: str = None        # the mesh file's name in the case folder
    mesh_bytes: bytes = None
    weight: float = 1.0     # how often it is drawn (the fine meshes are slow)

    def groups(self):
        return parse(self.text)

    def has(self, group):
        return any(g.name == group for g in self.groups())


def load_seeds():
    seeds = []
    for name in sorted(os.listdir(INPUTS)):
        if not name.endswith('.nml'):
            continue
        with open(os.path.join(INPUTS, name), encoding='latin-1') as f:
            text = f.read()      # bytes as characters: written back unchanged
        seed = Seed(name[:-4], text)
        m = re.search(r"mesh_file\s*=\s*'([^']*)'", text)
        if m:
            # the mesh is copied beside the variant, which names the copy
            with open(os.path.join(INPUTS, m.group(1)), 'rb') as f:
                seed.mesh_bytes = f.read()
            seed.mesh = os.path.basename(m.group(1))
            seed.text = text.replace(m.group(0), "mesh_file = '%s'" % seed.mesh)
            seed.weight = 0.1
        seeds.append(seed)
    # a small body on a mesh file: the cantilever on bar_hex8.mesh
    with open(os.path.join(INPUTS, 'flexible_cantilever.nml'), encoding='latin-1') as f:
        text = f.read()
    text = re.sub(r"\n\s*divisions = [^\n]*", '', text)
    text = re.sub(r"\n\s*lengths\s*= [^\n]*", '', text)
    text = text.replace("element   = 'hex8'", "element   = 'hex8'\n    mesh_file = 'bar.mesh'")
    text = text.replace("fixed     = 'xmin'", "fixed     = 'clamp'")
    text = text.replace("elements = 'xmax_layer'", "elements = 'tip_layer'")
    with open(os.path.join(INPUTS, 'meshes', 'bar_hex8.mesh'), 'rb') as f:
        seeds.append(Seed('bar_mesh', text, 'bar.mesh', f.read(), 1.0))
    for s in seeds:
        s.groups()   # every seed must parse
    return seeds


# ----------------------------------------------------------------------
# Operators: each makes one variant of a seed
# ----------------------------------------------------------------------

@dataclass
class Variant:
    seed: Seed
    text: str
    detail: str
    mesh_bytes: bytes = None
    targeted: set = field(default_factory=set)   # variables the cut must leave alone
    invalid: bool = False                         # the operator makes it bad input
    hostile: bool = False                         # the operator sets the paths
    scene: str = 'scene.nml'                      # the scene's name in the case folder
    specials: list = field(default_factory=list)  # (kind, path[, target]) made before the run
    extra: dict = field(default_factory=dict)     # more files: name -> bytes
    output: str = 'out.h5'                        # where a valid run writes (None: nowhere)
    fixed_output: bool = False                    # the operator chose the output


def pick_seed(rng, seeds, want=None):
    pool = [s for s in seeds if want is None or want(s)]
    return rng.choices(pool, weights=[s.weight for s in pool])[0]


def all_assigns(seed):
    return [(g, a) for g in seed.groups() for a in g.assigns]


def kind_of(schema, g, a):
    return schema.get((g.name, a.name), ('unknown', 1))


def op_delete(rng, seeds, schema):
    seed = pick_seed(rng, seeds)
    t = seed.text
    how = rng.choice(['line', 'assignment', 'group', 'item', 'char', 'mesh line'])
    if how == 'mesh line' and not seed.mesh:
        how = 'line'
    multi = [(g, a) for g, a in all_assigns(seed) if len(a.items) > 1]
    if how == 'item' and not multi:
        how = 'assignment'
    if how == 'line':
        lines = t.split('\n')
        k = rng.randrange(len(lines))
        return Variant(seed, '\n'.join(lines[:k] + lines[k + 1:]),
                       'delete line %d: %r' % (k + 1, lines[k][:60]))
    if how == 'mesh line':
        lines = seed.mesh_bytes.split(b'\n')
        k = rng.randrange(len(lines))
        return Variant(seed, t, 'delete mesh line %d: %r' % (k + 1, lines[k][:60]),
                       mesh_bytes=b'\n'.join(lines[:k] + lines[k + 1:]))
    if how == 'assignment':
        g, a = rng.choice(all_assigns(seed))
        end = a.end
        m = re.match(r'\s*,', t[end:])
        if m:
            end += m.end()
        return Variant(seed, replace(t, a.start, end, ''), 'delete &%s %s' % (g.name, a.name),
                       targeted={a.name})
    if how == 'group':
        g = rng.choice(seed.groups())
        return Variant(seed, replace(t, g.start, g.end, ''), 'delete group &%s' % g.name,
                       targeted={a.name for a in g.assigns})
    if how == 'item':
        g, a = rng.choice(multi)
        k = rng.randrange(len(a.items))
        s, e = a.items[k]
        if k > 0:
            s = a.items[k - 1][1]       # with the comma before it
        else:
            e = a.items[1][0]
        kind = kind_of(schema, g, a)[0]
        return Variant(seed, replace(t, s, e, ''), 'delete value %d of &%s %s' %
                       (k + 1, g.name, a.name), targeted={a.name},
                       invalid=kind in ('real', 'integer'))
    # one structural character
    spots = [i for i, c in enumerate(t) if c in "&/=,'"]
    i = rng.choice(spots)
    return Variant(seed, replace(t, i, i + 1, ''), 'delete %r at offset %d' % (t[i], i))


def op_truncate(rng, seeds, schema):
    seed = pick_seed(rng, seeds)
    if seed.mesh and rng.random() < 0.5:
        k = rng.randrange(len(seed.mesh_bytes))
        return Variant(seed, seed.text, 'truncate the mesh at byte %d of %d' %
                       (k, len(seed.mesh_bytes)), mesh_bytes=seed.mesh_bytes[:k])
    k = rng.randrange(len(seed.text))
    return Variant(seed, seed.text[:k], 'truncate at byte %d of %d' % (k, len(seed.text)))


def flip(rng, data):
    data = bytearray(data)
    done = []
    for _ in range(rng.randint(1, 3)):
        i = rng.randrange(len(data))
        r = rng.random()
        if r < 0.4:
            b = rng.randrange(256)
        elif r < 0.7:
            b = rng.choice(b"&/=,'\"!\n\t\r\x00.-+eE ")
        else:
            b = rng.choice(b'abcxyzXYZ0123456789_')
        done.append('%d:%r->%r' % (i, bytes([data[i]]), bytes([b])))
        data[i] = b
    return bytes(data), ' '.join(done)


def op_byte_flip(rng, seeds, schema):
    seed = pick_seed(rng, seeds)
    if seed.mesh and rng.random() < 0.5:
        data, what = flip(rng, seed.mesh_bytes)
        return Variant(seed, seed.text, 'flip mesh bytes ' + what, mesh_bytes=data)
    data, what = flip(rng, seed.text.encode('latin-1'))
    return Variant(seed, data.decode('latin-1'), 'flip bytes ' + what)


WRONG = {
    'real': ["'1.0'", '.true.', 'one', '1.0.0', '1e', '1.5e+', '--1', '0x1F', '1_wp', '(1.0',
             'T', '1.0q0', "''", '1e5.0'],
    'integer': ['1.5', '1e3', "'3'", '.false.', 'three', '3.', '0x3', '1_8', '2d0', '+', '1-'],
    'logical': ['1', '0', "'yes'", 'yes', '.maybe.', '2.0', "'.true.'", 'on'],
    'string': ['radau5', '3', '.true.', "'unterminated", "\"mixed'", 'a b', '1.0'],
}


def one_value(rng, seed, schema, table, invalid):
    """One value of a variable whose kind is a key of `table` replaced by one
    of table[kind]; invalid(value): whether that makes the scene bad input."""
    g, a = rng.choice([(g, a) for g, a in all_assigns(seed) if kind_of(schema, g, a)[0] in table])
    kind = kind_of(schema, g, a)[0]
    k = rng.randrange(len(a.items))
    value = rng.choice(table[kind])
    s, e = a.items[k]
    return Variant(seed, replace(seed.text, s, e, value), '&%s %s: value %d (%s) = %s' %
                   (g.name, a.name, k + 1, kind, value), targeted={a.name},
                   invalid=invalid(value))


def mesh_tokens(seed, pattern):
    """(start, end) of the mesh file's tokens that match `pattern`, comments left out."""
    text = seed.mesh_bytes.decode('latin-1')
    found = []
    for line in re.finditer(r'[^\n]*', text):
        body = line.group(0).split('#', 1)[0]
        for m in re.finditer(r'\S+', body):
            if re.fullmatch(pattern, m.group(0)):
                found.append((line.start() + m.start(), line.start() + m.end()))
    return text, found


def mesh_token(rng, seed, pattern, values, what, invalid):
    """The variant with one mesh token matching `pattern` replaced by one of `values`."""
    text, found = mesh_tokens(seed, pattern)
    s, e = rng.choice(found)
    value = rng.choice(values)
    return Variant(seed, seed.text, 'mesh %s %r at byte %d = %s' % (what, text[s:e], s, value),
                   mesh_bytes=replace(text, s, e, value).encode('latin-1'),
                   invalid=invalid(value))


def op_wrong_type(rng, seeds, schema):
    return one_value(rng, pick_seed(rng, seeds), schema, WRONG, lambda value: True)

SPECIAL = {
    'real': ['nan', 'NaN', '+Inf', '-inf', 'Infinity', '1e999', '-1e999', '1.8e308',
             '1.7976931348623157e308', '-1.7976931348623157e308', '4.9e-324', '1e-310', '0',
             '0.0', '-0.0', '-1', '-1e-300', '1e300', '-1e30', '1e30', '1e-30', '1d300',
             '-2.5e-16'],
    'integer': ['0', '-1', '-2147483648', '2147483647', '2147483648', '-2147483649',
                '9223372036854775808', '99999999999999999999', '1', '2', '-0', '+7'],
}
# a real text the scene reader must refuse: not a number, or beyond the reals
NOT_FINITE = {'nan', 'NaN', '+Inf', '-inf', 'Infinity', '1e999', '-1e999', '1.8e308'}
BEYOND_INT = {'2147483648', '-2147483649', '9223372036854775808', '99999999999999999999'}
MESH_SPECIAL = ['nan', 'inf', '-Infinity', '1e999', '-1e999', '1e308', '-1e308', '0', '-1',
                '2147483648', '1e-320', '1.5', '-0', '1d0', '+3', '0.0e0']


def op_special_value(rng, seeds, schema):
    seed = pick_seed(rng, seeds)
    if seed.mesh and rng.random() < 0.4:
        return mesh_token(rng, seed, r'[-+0-9.eE]+', MESH_SPECIAL, 'number',
                          lambda value: value in ('nan', 'inf', '-Infinity'))
    return one_value(rng, seed, schema, SPECIAL,
                     lambda value: value in NOT_FINITE or value in BEYOND_INT)


def op_unknown_name(rng, seeds, schema):
    seed = pick_seed(rng, seeds)
    if seed.mesh and rng.random() < 0.4:
        return mesh_token(rng, seed, r'(?i)flexmbs-mesh|nodes|elements|hex8|node_set|'
                          r'element_set', ['nodez', 'node', 'hex9', 'hex', 'faces', 'set',
                                           'flexmbs_mesh', 'elementset', '_'],
                          'keyword', lambda value: True)
    t = seed.text
    how = rng.choice(['variable', 'variable', 'group', 'stray text'])
    if how == 'variable':
        g, a = rng.choice(all_assigns(seed))
        others = sorted({n for (gr, n) in schema if gr != g.name and (g.name, n) not in schema})
        new = rng.choice([a.name + 'x', 'x' + a.name, a.name + '(1)', a.name + '%x',
                          'frobnicate', a.name.replace('_', '-') if '_' in a.name else a.name
                          + '_', rng.choice(others), a.name[:-1] or 'q'])
        if (g.name, new.lower()) in schema:
            new = new + 'zz'
        return Variant(seed, replace(t, a.start, a.start + len(a.name), new),
                       '&%s: %s renamed %s' % (g.name, a.name, new), targeted={a.name},
                       invalid=True)
    if how == 'group':
        g = rng.choice(seed.groups())
        new = rng.choice([g.name + 's', g.name[:-1], 'end', 'study', 'namelist', '',
                          g.name + '_1', 'x' + g.name])
        return Variant(seed, replace(t, g.start + 1, g.start + 1 + len(g.name), new),
                       '&%s renamed &%s' % (g.name, new), targeted={a.name for a in g.assigns},
                       invalid=True)
    g = rng.choice(seed.groups())
    stray = rng.choice(['hello', 'rtol = 1e-6', '/', '1.0', "'text'", '$end', '= 3', '%'])
    at = rng.choice([g.start, g.end])
    return Variant(seed, replace(t, at, at, '\n' + stray + '\n'),
                   'stray %r before offset %d' % (stray, at), invalid=True)


NAMED_ONCE = {'rigid_body', 'marker', 'material', 'rigid_chain'}


def op_duplicate(rng, seeds, schema):
    seed = pick_seed(rng, seeds)
    if seed.mesh and rng.random() < 0.4:
        lines = seed.mesh_bytes.split(b'\n')
        k = rng.randrange(len(lines))
        return Variant(seed, seed.text, 'mesh line %d given twice: %r' % (k + 1, lines[k][:60]),
                       mesh_bytes=b'\n'.join(lines[:k + 1] + lines[k:]))
    t = seed.text
    how = rng.choice(['variable', 'variable', 'group', 'empty group'])
    if how == 'variable':
        g, a = rng.choice(all_assigns(seed))
        copy = t[a.start:a.end]
        if rng.random() < 0.5:
            copy = copy[:len(a.name)].upper() + copy[len(a.name):]
        return Variant(seed, replace(t, a.end, a.end, ', ' + copy),
                       '&%s %s given twice' % (g.name, a.name), targeted={a.name}, invalid=True)
    if how == 'group':
        g = rng.choice(seed.groups())
        named = any(a.name == 'name' for a in g.assigns)
        invalid = g.name not in {'joint', 'driver'} | NAMED_ONCE or \
            (g.name in NAMED_ONCE and (named or g.name == 'material'))
        return Variant(seed, replace(t, g.end, g.end, '\n' + t[g.start:g.end]),
                       'group &%s given twice' % g.name, invalid=invalid)
    groups = [g for g in seed.groups() if g.name not in {'joint', 'driver'} | NAMED_ONCE]
    g = rng.choice(groups)
    return Variant(seed, t + '\n&%s /\n' % g.name, 'an empty &%s after the first' % g.name,
                   invalid=True)


# (group, variable): what a reference names
REFERENCES = [('marker', 'body'), ('joint', 'marker_i'), ('joint', 'marker_j'),
              ('driver', 'marker_i'), ('driver', 'marker_j'), ('rigid_chain', 'parent'),
              ('marker', 'node_set'), ('flexible_body', 'fixed'), ('flexible_body', 'load_set'),
              ('material', 'elements'), ('flexible_body', 'mesh_file')]


def op_broken_reference(rng, seeds, schema):
    def refs(seed):
        return [(g, a) for g, a in all_assigns(seed) if (g.name, a.name) in REFERENCES]
    seed = pick_seed(rng, seeds, lambda s: refs(s))
    g, a = rng.choice(refs(seed))
    names = [seed.text[s + 1:e - 1] for gg in seed.groups() for aa in gg.assigns
             if aa.name == 'name' for s, e in aa.items]
    if a.name == 'mesh_file':
        new = rng.choice(["'missing.mesh'", "'sub/bar.mesh'", "''"])
        if new == "''":
            # an empty mesh_file means a box, which then lacks its lengths
            new = "'nothing.mesh'"
    elif a.name == 'parent':
        own = [seed.text[s + 1:e - 1] for aa in g.assigns if aa.name == 'name'
               for s, e in aa.items]
        later = names[names.index(own[0]) + 1:] if own and own[0] in names else []
        new = "'%s'" % rng.choice(['nowhere', 'Ground', ''] + own + later)
    elif a.name == 'body':
        flexible = [n for gg in seed.groups() if gg.name == 'flexible_body'
                    for aa in gg.assigns if aa.name == 'name'
                    for n in [seed.text[aa.items[0][0] + 1:aa.items[0][1] - 1]]]
        has_node_set = any(aa.name == 'node_set' for aa in g.assigns)
        choices = ['nowhere', 'Ground', '']
        if flexible and not has_node_set:
            choices.append(flexible[0])
        new = "'%s'" % rng.choice(choices)
    elif a.name in ('marker_i', 'marker_j'):
        joints = [n for gg in seed.groups() if gg.name in ('joint', 'driver')
                  for aa in gg.assigns if aa.name == 'name'
                  for n in [seed.text[aa.items[0][0] + 1:aa.items[0][1] - 1]]]
        markers = {seed.text[aa.items[0][0] + 1:aa.items[0][1] - 1] for gg in seed.groups()
                   if gg.name == 'marker' for aa in gg.assigns if aa.name == 'name'}
        choices = ['nowhere', 'ground', ''] + [j for j in joints if j not in markers]
        new = "'%s'" % rng.choice(choices)
    else:
        new = "'%s'" % rng.choice(['nowhere', 'xmin2', 'clamp2', 'tip layer'])
    k = rng.randrange(len(a.items))
    s, e = a.items[k]
    return Variant(seed, replace(seed.text, s, e, new), '&%s %s = %s' % (g.name, a.name, new),
                   targeted={a.name}, invalid=True)


def set_in_group(text, group, name, value):
    """The text with `name = value` in the first &group (replaced or added)."""
    m = re.search(r'(?im)^&' + group + r'\b', text)
    if not m:
        return text + '\n&%s %s = %s /\n' % (group, name, value)
    end = text.find('/', m.end())
    while end >= 0 and text.count("'", m.end(), end) % 2:
        end = text.find('/', end + 1)
    body = text[m.end():end]
    v = re.search(r'(?i)\b' + name + r"\s*=\s*('[^'\n]*'|[^\s,/!]+)", body)
    if v:
        return text[:m.end() + v.start(1)] + value + text[m.end() + v.end(1):]
    return text[:m.end()] + ' %s = %s,' % (name, value) + text[m.end():]


def op_hostile_path(rng, seeds, schema):
    """Paths that point where an output must not go, or inputs that are no files."""
    hows = ['out is scene', 'out is scene by link', 'out is mesh', 'out is folder',
            'out in missing folder', 'out is device', 'out is fifo', 'scene is fifo',
            'scene is folder', 'scene is device', 'mesh is fifo', 'mesh is folder',
            'mesh is device', 'table is scene', 'table in missing folder', 'vtk is scene',
            'vtk in missing folder', 'out escapes up', 'out too long', 'out odd name',
            'out overwrites a file', 'out is scene by hard link', 'scene by link, out is it',
            'table is mesh', 'out is none', 'scene missing']
    how = rng.choice(hows)
    if how.startswith('mesh') or how in ('out is mesh', 'table is mesh'):
        seed = pick_seed(rng, seeds, lambda s: s.mesh)
    elif how.startswith('vtk'):
        seed = pick_seed(rng, seeds, lambda s: s.has('flexible_body') or s.has('rigid_body'))
    else:
        seed = pick_seed(rng, seeds)
    t = seed.text
    v = Variant(seed, t, how, hostile=True, invalid=True, fixed_output=True, output=None)

    def out(path):
        v.text = set_in_group(v.text, 'output', 'file', "'%s'" % path.replace("'", "''"))
    if how == 'out is scene':
        out(rng.choice(['scene.nml', './scene.nml', 'sub/../scene.nml', '{work}/scene.nml']))
        v.specials.append(('dir', 'sub'))
    elif how == 'out is scene by link':
        v.specials.append(('symlink', 'link.h5', 'scene.nml'))
        out('link.h5')
    elif how == 'out is scene by hard link':
        v.specials.append(('hardlink', 'hard.h5', 'scene.nml'))
        out('hard.h5')
    elif how == 'scene by link, out is it':
        v.scene = 'alias.nml'
        v.extra['real.nml'] = None      # the scene text, under another name
        v.specials.append(('symlink', 'alias.nml', 'real.nml'))
        out('real.nml')
    elif how == 'out is mesh':
        out(rng.choice([seed.mesh, './' + seed.mesh, '{work}/' + seed.mesh]))
    elif how == 'out is folder':
        v.specials.append(('dir', 'sub'))
        out(rng.choice(['.', 'sub', 'sub/', '..', '{work}']))
    elif how == 'out in missing folder':
        out(rng.choice(['missing/x.h5', 'missing/deeper/x.h5', 'scene.nml/x.h5']))
    elif how == 'out is device':
        v.specials.append(('null', 'null'))
        out('null')
    elif how == 'out is fifo':
        v.specials.append(('fifo', 'pipe'))
        out('pipe')
    elif how == 'scene is fifo':
        v.specials.append(('fifo', 'pipe.nml'))
        v.scene = 'pipe.nml'
    elif how == 'scene is folder':
        v.specials.append(('dir', 'folder.nml'))
        v.scene = rng.choice(['folder.nml', 'folder.nml/'])
    elif how == 'scene missing':
        v.scene = rng.choice(['missing.nml', 'sub/missing.nml', 'scene.nml.bak'])
        v.extra['scene.nml'] = None
        v.specials.append(('absent', v.scene))
    elif how == 'scene is device':
        v.specials.append(('null', 'null.nml'))
        v.scene = 'null.nml'
    elif how in ('mesh is fifo', 'mesh is folder', 'mesh is device'):
        kind = {'mesh is fifo': 'fifo', 'mesh is folder': 'dir', 'mesh is device': 'null'}[how]
        v.specials.append((kind, 'special.mesh'))
        v.text = v.text.replace("mesh_file = '%s'" % seed.mesh, "mesh_file = 'special.mesh'")
        out('out.h5')
    elif how == 'table is scene':
        v.scene = 'scene.md'
        out('out.h5')
        v.text = set_in_group(v.text, 'output', 'table', "'scene.md'")
    elif how == 'table is mesh':
        v.extra['bar.md'] = seed.mesh_bytes
        v.text = v.text.replace("mesh_file = '%s'" % seed.mesh, "mesh_file = 'bar.md'")
        out('out.h5')
        v.text = set_in_group(v.text, 'output', 'table', "'bar.md'")
    elif how == 'table in missing folder':
        out('out.h5')
        v.text = set_in_group(v.text, 'output', 'table', "'missing/t.md'")
    elif how == 'vtk is scene':
        v.scene = 'v.pvd'
        out('out.h5')
        v.text = set_in_group(v.text, 'output', 'vtk', "'v'")
    elif how == 'vtk in missing folder':
        out('out.h5')
        v.text = set_in_group(v.text, 'output', 'vtk', "'missing/v'")
    elif how == 'out escapes up':
        out('../escape.h5')
        v.invalid, v.output = False, '../escape.h5'
    elif how == 'out too long':
        out('x' * 600 + '.h5')
    elif how == 'out odd name':
        name = rng.choice(["a b.h5", "it's.h5", "é.h5", "-x.h5", " lead.h5", "x.h5 ",
                           "semi;colon&amp.h5", "tab\there.h5"])
        out(name.encode('utf-8').decode('latin-1'))   # the text holds bytes
        v.invalid, v.output = False, name
    elif how == 'out overwrites a file':
        v.extra['old.h5'] = b'not an HDF5 file, may be replaced\n'
        out('old.h5')
        v.invalid, v.output = False, 'old.h5'
    elif how == 'out is none':
        out(rng.choice(['none', 'NONE', '']))
        v.invalid, v.output = False, None
    return v


def op_oversized(rng, seeds, schema):
    hows = ['divisions', 'mesh nodes', 'mesh elements', 'mesh set', 'n_output', 'npoints',
            'many values', 'fixed sets', 'long string', 'long name', 'many groups',
            'long comment', 'many lines', 'long and many lines', 'max_steps', 'many items']
    how = rng.choice(hows)
    if how == 'divisions':
        seed = pick_seed(rng, seeds, lambda s: 'divisions' in s.text)
        m = re.search(r'divisions\s*=\s*[0-9, ]*[0-9]', seed.text)
        new = rng.choice(['2000, 2000, 2000', '2147483647, 1, 1', '400, 400, 400',
                          '100000, 100000, 1', '1290, 1290, 1290', '65536, 65536, 2'])
        return Variant(seed, replace(seed.text, m.start(), m.end(), 'divisions = ' + new),
                       'divisions = ' + new, targeted={'divisions'}, invalid=True)
    if how.startswith('mesh'):
        seed = pick_seed(rng, seeds, lambda s: s.mesh)
        mesh = seed.mesh_bytes.decode('latin-1')
        big = rng.choice(['2000000000', '2147483647', '99999999999', '1000000000', '300000000'])
        key = {'mesh nodes': r'(?m)^(nodes )(\d+)', 'mesh elements': r'(?m)^(elements \w+ )(\d+)',
               'mesh set': r'(?m)^((?:node|element)_set \w+ )(\d+)'}[how]
        ms = list(re.finditer(key, mesh))
        m = rng.choice(ms)
        mesh = mesh[:m.start(2)] + big + mesh[m.end(2):]
        return Variant(seed, seed.text, '%s: %r' % (how, m.group(1) + big),
                       mesh_bytes=mesh.encode('latin-1'), invalid=True)
    if how == 'n_output':
        seed = pick_seed(rng, seeds)
        value = rng.choice(['2147483647', '1000000000'])
        return Variant(seed, set_in_group(seed.text, 'output', 'n_output', value),
                       'n_output = ' + value, targeted={'n_output'}, invalid=True)
    if how == 'npoints':
        seed = next(s for s in seeds if s.name == 'van_der_pol')
        value = rng.choice(['2147483647', '100000', '50000', '1000000'])
        text = seed.text.replace("'van_der_pol'", "'brusselator_%s'" % rng.choice('12'))
        if 'brusselator_1' in text and value in ('100000', '50000'):
            value = '2147483647'
        text = set_in_group(text, 'simulation', 'npoints', value)
        return Variant(seed, text, 'npoints = %s, %s' % (value, re.search(
            r"brusselator_\d", text).group(0)), targeted={'npoints'}, invalid=True)
    if how == 'many values':
        seed = pick_seed(rng, seeds, lambda s: re.search(r'gravity\s*=\s*\S+,', s.text))
        m = re.search(r'(gravity\s*=\s*)([-0-9., ]*[0-9])', seed.text)
        values = ', '.join(['1.0'] * rng.choice([4, 100, 50000]))
        return Variant(seed, replace(seed.text, m.start(2), m.end(2), values),
                       'gravity with %d values' % (values.count(',') + 1), invalid=True)
    if how == 'fixed sets':
        seed = pick_seed(rng, seeds, lambda s: 'fixed ' in s.text)
        m = re.search(r"fixed\s*=\s*'[^']*'", seed.text)
        n = rng.choice([7, 1000])
        return Variant(seed, replace(seed.text, m.start(), m.end(), 'fixed = ' + ', '.join(
            ["'xmin'"] * n)), 'fixed with %d sets' % n, invalid=True)
    if how == 'long string':
        seed = pick_seed(rng, seeds, lambda s: 'title' in s.text)
        n = rng.choice([257, 100000])
        return Variant(seed, set_in_group(seed.text, 'simulation', 'title', "'" + 'x' * n + "'"),
                       'title of %d characters' % n, invalid=True)
    if how == 'long name':
        seed = pick_seed(rng, seeds)
        n = rng.choice([100, 100000])
        return Variant(seed, set_in_group(seed.text, 'simulation', 'y' * n, '1.0'),
                       'a variable name of %d characters' % n, invalid=True)
    if how == 'many groups':
        seed = pick_seed(rng, seeds, lambda s: s.has('marker') and s.weight == 1.0)
        n = rng.choice([500, 4000])
        extra = ''.join("&marker name = 'm%d', body = 'ground', position = %d.0, 0.0, 0.0 /\n"
                        % (i, i) for i in range(n))
        return Variant(seed, seed.text + extra, '%d more &marker groups' % n)
    if how == 'long comment':
        seed = pick_seed(rng, seeds)
        g = rng.choice(seed.groups())
        n = rng.choice([10000, 1000000])
        at = g.start + 1 + len(g.name)
        return Variant(seed, replace(seed.text, at, at, ' ! ' + 'c' * n + '\n'),
                       'a comment of %d characters in &%s' % (n, g.name))
    if how == 'many lines':
        seed = pick_seed(rng, seeds)
        g = rng.choice(seed.groups())
        n = rng.choice([1000, 100000])
        at = g.start + 1 + len(g.name)
        return Variant(seed, replace(seed.text, at, at, '\n' * n),
                       '%d blank lines in &%s' % (n, g.name))
    if how == 'long and many lines':
        # a group's text is read through records as long as its longest line
        seed = pick_seed(rng, seeds)
        g = rng.choice(seed.groups())
        lines, width = rng.choice([(100000, 1000000), (20000, 100000), (2000, 10000)])
        at = g.start + 1 + len(g.name)
        return Variant(seed, replace(seed.text, at, at, ' ! ' + 'c' * width + '\n' * lines),
                       '%d lines and a comment of %d characters in &%s' % (lines, width,
                                                                         g.name))
    if how == 'max_steps':
        seed = pick_seed(rng, seeds)
        return Variant(seed, set_in_group(seed.text, 'solver', 'max_steps', '2147483647'),
                       'max_steps = 2147483647', targeted={'max_steps'})
    # many items of a list where one is expected
    seed = pick_seed(rng, seeds)
    g, a = rng.choice([(g, a) for g, a in all_assigns(seed) if kind_of(schema, g, a)[1] == 1])
    s, e = a.items[-1]
    n = rng.choice([2, 1000])
    return Variant(seed, replace(seed.text, s, e, ', '.join([seed.text[s:e]] * n)),
                   '&%s %s with %d values' % (g.name, a.name, n), targeted={a.name},
                   invalid=True)


# (group, variable): the words it takes
SOLVER_CHOICES = {
    'name': ['radau5', 'ddassl', 'ida', 'mexax'],
    'linear_solver': ['dense', 'band', 'klu', 'mumps', 'auto'],
    'sparse_ordering': ['auto', 'amd', 'nd'],
    'jacobian': ['analytic', 'fd'],
    'controller': ['predictive', 'classical'],
    'mexax_base': ['midpoint', 'euler'],
}
FORMULATIONS = ['index3', 'index2', 'index1', 'ggl']
CHOICES = {('solver', k): v for k, v in SOLVER_CHOICES.items()}
CHOICES.update({
    ('simulation', 'problem'): ['van_der_pol', 'pendulum', 'robertson', 'brusselator_1d',
                                'flexible_body', 'multibody', 'rigid_chain'],
    ('simulation', 'pendulum_formulation'): FORMULATIONS,
    ('multibody', 'formulation'): FORMULATIONS,
    ('flexible_body', 'formulation'): FORMULATIONS,
    ('flexible_body', 'element'): ['hex8', 'hex27'],
    ('joint', 'type'): ['spherical', 'revolute', 'cylindrical', 'prismatic', 'universal',
                        'fixed', 'attach'],
    ('driver', 'type'): ['angle', 'translation', 'distance'],
    ('rigid_chain', 'joint'): ['revolute', 'prismatic', 'spherical'],
    ('multibody', 'constraint_derivatives'): ['analytic', 'ad', 'ad_full'],
})


def op_other_choice(rng, seeds, schema):
    """Another valid word for a choice, or the other logical: valid alone, maybe not together."""
    def pool(seed):
        return [(g, a) for g, a in all_assigns(seed) if (g.name, a.name) in CHOICES
                or kind_of(schema, g, a)[0] == 'logical']
    seed = pick_seed(rng, seeds, lambda s: s.weight == 1.0 and pool(s))
    # the solver's settings thrice as often: their checks come late, in the run
    g, a = rng.choices(pool(seed), weights=[3 if g.name == 'solver' else 1
                                            for g, a in pool(seed)])[0]
    s, e = a.items[0]
    if kind_of(schema, g, a)[0] == 'logical':
        new = '.false.' if 't' in seed.text[s:e].lower() else '.true.'
    else:
        new = "'%s'" % rng.choice([c for c in CHOICES[(g.name, a.name)]
                                   if "'%s'" % c != seed.text[s:e]])
    text = replace(seed.text, s, e, new)
    if (g.name, a.name) == ('solver', 'name') and rng.random() < 0.5:
        text = set_in_group(text, 'solver', 'pmax', rng.choice(['5', '6', '12']))
    return Variant(seed, text, '&%s %s = %s' % (g.name, a.name, new))


OPERATORS = [
    ('delete', op_delete),
    ('truncate', op_truncate),
    ('byte flip', op_byte_flip),
    ('wrong type', op_wrong_type),
    ('special value', op_special_value),
    ('unknown name', op_unknown_name),
    ('duplicate', op_duplicate),
    ('broken reference', op_broken_reference),
    ('hostile path', op_hostile_path),
    ('oversized', op_oversized),
    ('other choice', op_other_choice),
]


def cut(v):
    """A few steps: t_end, n_output and max_steps made small, the output put in
    the case folder, unless the operator aims at them."""
    t = v.text
    if 't_end' not in v.targeted:
        start = 0.0
        m = re.search(r'(?i)\bt_start\s*=\s*([-+0-9.eEdD]+)', t)
        if m:
            try:
                start = float(m.group(1).lower().replace('d', 'e'))
            except ValueError:
                pass
        t = re.sub(r'(?i)(\bt_end\s*=\s*)[-+0-9.eEdD]+', lambda m: m.group(1) + repr(
            start + END_TIME_STEP), t, count=1)
    if 'n_output' not in v.targeted:
        t = re.sub(r'(?i)(\bn_output\s*=\s*)[-+0-9]+', r'\g<1>2', t, count=1)
    if 'max_steps' not in v.targeted and re.search(r'(?im)^&solver\b', t):
        t = set_in_group(t, 'solver', 'max_steps', str(MAX_STEPS))
    if not v.fixed_output and re.search(r'(?im)^&output\b', t):
        t = set_in_group(t, 'output', 'file', "'out.h5'")
    elif not v.fixed_output:
        v.output = os.path.splitext(v.scene)[0] + '.h5'   # the default name
    v.text = t


# ----------------------------------------------------------------------
# Cases
# ----------------------------------------------------------------------

@dataclass
class Case:
    ident: str
    operator: str
    variant: Variant


def make_case(index, seed, seeds, schema):
    rng = random.Random('%d:%d' % (seed, index))
    name, op = OPERATORS[index % len(OPERATORS)]
    variant = op(rng, seeds, schema)
    cut(variant)
    return Case(str(index), name, variant)


def saved_cases(seeds):
    cases = []
    if not os.path.isdir(SAVED):
        return cases
    bar = next(s for s in seeds if s.name == 'bar_mesh')
    for name in sorted(os.listdir(SAVED)):
        if not name.endswith('.nml'):
            continue
        with open(os.path.join(SAVED, name), encoding='latin-1') as f:
            text = f.read()
        mesh = os.path.join(SAVED, name[:-4] + '.mesh')
        seed = Seed(name[:-4], text, 'bar.mesh', bar.mesh_bytes)
        v = Variant(seed, text, 'saved reproducer', fixed_output=True)
        if os.path.exists(mesh):
            with open(mesh, 'rb') as f:
                v.mesh_bytes = f.read()
        first = text.split('\n', 1)[0]
        v.invalid = 'exit 2' in first
        m = re.search(r"file\s*=\s*'([^']*)'", text)
        v.output = m.group(1) if m else 'scene.h5'
        cases.append(Case('cases/' + name[:-4], 'saved', v))
    return cases


def safe_paths(case, work):
    """Every quoted string of the variant, taken as a path from the case's
    work folder, stays inside the case folder (a flip may make '/...')."""
    inside = os.path.dirname(work)
    for s in re.findall(r"'([^'\n]*)'|\"([^\"\n]*)\"", case.variant.text):
        s = (s[0] or s[1]).replace('{work}', work)
        if '/' not in s and '..' not in s:
            continue
        full = os.path.normpath(os.path.join(work, s))
        if full != inside and not full.startswith(inside + os.sep):
            return False
    return True


def materialise(case, work):
    v = case.variant
    os.makedirs(work)
    text = v.text.replace('{work}', work)
    files = {v.scene: text.encode('latin-1')}
    if v.seed.mesh:
        files[v.seed.mesh] = v.mesh_bytes if v.mesh_bytes is not None else v.seed.mesh_bytes
    for name, data in v.extra.items():
        files[name] = text.encode('latin-1') if data is None else data
    for kind, path, *target in v.specials:
        full = os.path.join(work, path)
        if kind == 'dir':
            os.makedirs(full, exist_ok=True)
        elif kind == 'fifo':
            os.mkfifo(full)
        elif kind == 'null':
            try:  # a character device like /dev/null, inside the case folder
                os.mknod(full, stat.S_IFCHR | 0o666, os.makedev(1, 3))
            except OSError:
                os.mkfifo(full)
        if kind in ('symlink', 'hardlink', 'absent'):
            files.pop(path, None)
    for name, data in files.items():
        if any(sp[1] == name.rstrip('/') and sp[0] in ('fifo', 'null', 'dir')
               for sp in v.specials):
            continue
        with open(os.path.join(work, name), 'wb') as f:
            f.write(data)
    for kind, path, *target in v.specials:
        if kind == 'symlink':
            os.symlink(target[0], os.path.join(work, path))
        elif kind == 'hardlink':
            os.link(os.path.join(work, target[0]), os.path.join(work, path))


def snapshot(folder):
    """{path: signature} of everything below folder, links and FIFOs not followed."""
    found = {}
    for dirpath, dirnames, filenames in os.walk(folder):
        for name in dirnames + filenames:
            path = os.path.join(dirpath, name)
            st = os.lstat(path)
            if stat.S_ISREG(st.st_mode):
                h = hashlib.sha256()
                with open(path, 'rb') as f:
                    for block in iter(lambda: f.read(1 << 20), b''):
                        h.update(block)
                sig = 'file ' + h.hexdigest()
            elif stat.S_ISLNK(st.st_mode):
                sig = 'link ' + os.readlink(path)
            elif stat.S_ISDIR(st.st_mode):
                sig = 'dir'
            else:
                sig = 'special %o' % stat.S_IFMT(st.st_mode)
            found[os.path.relpath(path, folder)] = sig
    return found


def readable_hdf5(path):
    """'' when path is an HDF5 file that opens, else why not."""
    if not os.path.isfile(path):
        return 'no file %s' % path
    if h5py is None:
        with open(path, 'rb') as f:
            return '' if f.read(8) == HDF5_SIGNATURE else 'no HDF5 signature'
    try:
        with h5py.File(path, 'r') as f:
            if 'time' not in f:
                return 'no /time in it'
            f['time'][()]
    except Exception as e:  # what h5py raises varies by version
        return 'h5py cannot read it: %s' % e
    return ''


def stage_of(message):
    body = message.split('flexmbs: ', 1)[-1]
    for name, patterns in STAGES:
        if any(re.search(p, body) for p in patterns):
            return name
    return None


@dataclass
class Result:
    case: Case
    code: int = None
    seconds: float = 0.0
    stdout: str = ''
    stderr: str = ''
    hang: bool = False
    crash: str = ''
    changed: list = field(default_factory=list)
    outputs: list = field(default_factory=list)
    problems: dict = field(default_factory=dict)   # property -> why
    stage: str = None
    skipped: str = ''


def time_limit(case):
    return TIME_LIMIT_FINE if case.variant.seed.weight < 1.0 else TIME_LIMIT


def run_case(case, exe, root, keep):
    r = Result(case)
    folder = os.path.join(root, 'case-' + case.ident.replace('/', '-'))
    work = os.path.join(folder, 'work')
    if not safe_paths(case, work):
        r.skipped = 'a path of the variant leaves the case folder'
        return r
    materialise(case, work)
    # a file beside the work folder, which no run may touch
    with open(os.path.join(folder, 'sentinel'), 'w') as f:
        f.write('outside the work folder\n')
    before = snapshot(folder)
    env = dict(os.environ, OPENBLAS_NUM_THREADS='1', OMP_NUM_THREADS='1',
               GFORTRAN_ERROR_BACKTRACE='1')
    start = time.monotonic()
    # the limits through the shell, which then becomes flexmbs (exec): a
    # preexec_fn is not safe beside the threads that run the cases
    limits = 'ulimit -v %d && ulimit -c 0 && exec "$0" "$@"' % (ADDRESS_LIMIT // 1024)
    p = subprocess.Popen(['sh', '-c', limits, exe, 'run', case.variant.scene, '--quiet'],
                         cwd=work, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, start_new_session=True)
    try:
        out, err = p.communicate(timeout=time_limit(case))
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
        r.hang = True
    r.seconds = time.monotonic() - start
    r.code = p.returncode
    r.stdout = out.decode('utf-8', 'replace')
    r.stderr = err.decode('utf-8', 'replace')
    after = snapshot(folder)
    # a file at the output's place is replaced by a run, as it should be
    replaced = os.path.relpath(os.path.normpath(os.path.join(work, case.variant.output or
                                                             '/')), folder)
    r.changed = sorted(k for k, sig in before.items() if after.get(k) != sig and not (
        k == replaced and p.returncode in (0, 3)))
    r.outputs = sorted(k for k in after if k not in before)
    judge(r, work)
    if not keep and not r.problems:
        shutil.rmtree(folder, ignore_errors=True)
    return r


def judge(r, work):
    v = r.case.variant
    text = r.stdout + '\n' + r.stderr
    if r.hang:
        r.problems['no-hang'] = 'no exit within %g s' % time_limit(r.case)
        return
    m = CRASH_PATTERNS.search(text)
    if r.code < 0:
        r.crash = 'signal %d' % -r.code
    elif m:
        r.crash = 'output has %r' % m.group(0)
    elif r.code not in (0, 2, 3):
        r.crash = 'exit %d' % r.code
    if r.crash:
        r.problems['no-crash'] = r.crash
    if r.changed:
        r.problems['inputs-unchanged'] = 'changed: ' + ', '.join(r.changed)
    if r.crash:
        return
    foreign = [line for line in r.stderr.split('\n') if line.strip()
               and not line.startswith('flexmbs: ')]
    if foreign:
        r.problems['own-messages'] = 'not flexmbs\'s: %r' % foreign[0][:200]
    if r.code == 2:
        if r.outputs:
            r.problems['exit-2-no-output'] = 'written: ' + ', '.join(r.outputs)
        first = r.stderr.strip().split('\n')[0] if r.stderr.strip() else ''
        if not first.startswith('flexmbs: ' + v.scene):
            r.problems['exit-2-message'] = 'does not start with the scene file: %r' % first[:300]
        elif RAW_MESSAGE.search(r.stderr):
            r.problems['exit-2-message'] = 'a raw runtime message: %r' % first[:300]
        r.stage = stage_of(first)
        if r.stage is None:
            r.problems['stages'] = 'no stage for %r' % first[:300]
    else:
        if v.invalid:
            r.problems['invalid-refused'] = 'exit %d for an invalid variant' % r.code
        if v.output:
            why = readable_hdf5(os.path.normpath(os.path.join(work, v.output)))
            if why:
                r.problems['valid-output'] = why


PROPERTIES = ['no-crash', 'no-hang', 'inputs-unchanged', 'exit-2-no-output', 'exit-2-message',
              'own-messages', 'valid-output', 'invalid-refused', 'stages', 'tally']


def find_exe():
    env = dict(os.environ)
    env.setdefault('FPM_FFLAGS', '-I/usr/include/hdf5/serial -I/usr/include/sundials/fortran '
                   '-I/usr/include -I/usr/include/mumps_seq')
    env.setdefault('FPM_CFLAGS', '-I/usr/include/suitesparse -fPIC')
    fpm = os.environ.get('FPM', 'fpm')
    try:
        out = subprocess.run([fpm, 'run', '--profile', 'debug', '--runner', 'echo', 'flexmbs'],
                             cwd=ROOT, env=env, capture_output=True, text=True).stdout
    except OSError:
        return ''
    lines = out.strip().split('\n')
    return os.path.join(ROOT, lines[-1].strip()) if lines and lines[-1].strip() else ''


def describe(r):
    v = r.case.variant
    return 'case %s [%s] %s: %s' % (r.case.ident, r.case.operator, v.seed.name, v.detail[:160])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--exe', help='the flexmbs executable (default: the debug build)')
    ap.add_argument('--cases', type=int, default=DEFAULT_CASES)
    ap.add_argument('--seed', type=int, default=DEFAULT_SEED)
    ap.add_argument('--jobs', type=int, default=2, help='cases at a time (at most 2)')
    ap.add_argument('--case', help='run this case alone (a number, or cases/NAME)')
    ap.add_argument('--keep', action='store_true', help='keep the case folders')
    ap.add_argument('--show', action='store_true', help='print the case, run nothing')
    ap.add_argument('--verbose', action='store_true', help='a line per case')
    args = ap.parse_args()

    schema = read_schema()
    seeds = load_seeds()
    saved = saved_cases(seeds)
    if args.case is not None:
        if args.case.startswith('cases/'):
            cases = [c for c in saved if c.ident == args.case]
        else:
            cases = [make_case(int(args.case), args.seed, seeds, schema)]
        if not cases:
            raise SystemExit('fuzz: no case %s' % args.case)
    else:
        cases = [make_case(i, args.seed, seeds, schema) for i in range(args.cases)] + saved
    if args.show:
        for c in cases:
            print('== ' + describe(Result(c)))
            print('-- %s (invalid: %s, output: %s)' % (c.variant.scene, c.variant.invalid,
                                                       c.variant.output))
            print(c.variant.text)
        return 0

    exe = os.path.abspath(args.exe) if args.exe else find_exe()
    if not exe or not os.access(exe, os.X_OK):
        print('FAIL fuzz: no executable (got %r)' % exe)
        print('0 passed, 1 failed')
        return 1
    root = tempfile.mkdtemp(prefix='flexmbs-fuzz.')
    started = time.monotonic()
    lock = threading.Lock()
    results = []

    def one(case):
        r = run_case(case, exe, root, args.keep or args.case is not None)
        with lock:
            if r.problems or args.verbose or args.case is not None:
                print(('FAIL ' if r.problems else 'ok   ') + describe(r) +
                      ' -> exit %s in %.1f s%s' % (r.code, r.seconds,
                                                    ', stage ' + r.stage if r.stage else ''))
                for prop, why in r.problems.items():
                    print('     %s: %s' % (prop, why))
                if args.verbose:
                    print('     ' + (r.stderr.strip().split('\n') or [''])[0][:300])
                if args.case is not None:
                    print('     folder: %s' % os.path.join(root, 'case-' + r.case.ident.replace(
                        '/', '-')))
                    print('     command: %s run %s --quiet' % (exe, r.case.variant.scene))
                    print('     stderr: ' + r.stderr.strip()[:2000].replace('\n', '\n     '))
                sys.stdout.flush()
        return r

    with ThreadPoolExecutor(max_workers=max(1, min(args.jobs, 2))) as pool:
        results = list(pool.map(one, cases))
    wall = time.monotonic() - started
    if not args.keep and args.case is None:
        shutil.rmtree(root, ignore_errors=True)
    return report(results, wall, single=args.case is not None)


def report(results, wall, single=False):
    ran = [r for r in results if not r.skipped]
    for r in results:
        if r.skipped:
            print('skip ' + describe(r) + ': ' + r.skipped)
    crashes = [r for r in ran if r.crash]
    hangs = [r for r in ran if r.hang]
    clean2 = [r for r in ran if r.code == 2 and not r.crash and not r.hang]
    invalid = [r for r in ran if r in clean2 or (r.case.variant.invalid and not r.crash
                                                 and not r.hang)]
    valid = [r for r in ran if r not in invalid and not r.crash and not r.hang]
    valid_ok = [r for r in valid if r.code in (0, 3)]
    leaks = [r for r in clean2 if r.outputs]
    changed = [r for r in ran if r.changed]
    print('fuzz: %d cases (%d invalid: %d exit 2; %d valid: %sexit 0/3), %d crashes, %d hangs, '
          '%d outputs after exit 2, %d inputs changed' % (
              len(ran), len(invalid), len(clean2), len(valid),
              '' if len(valid_ok) == len(valid) else '%d ' % len(valid_ok),
              len(crashes), len(hangs), len(leaks), len(changed)))
    for name, _ in OPERATORS + [('saved', None)]:
        mine = [r for r in ran if r.case.operator == name]
        if not mine:
            continue
        print('fuzz: operator %-16s %4d cases: %4d exit 2, %4d exit 0/3, %d failed' % (
            name, len(mine), sum(r.code == 2 and not r.crash for r in mine),
            sum(r.code in (0, 3) and not r.crash for r in mine),
            sum(bool(r.problems) for r in mine)))
    missing = []
    for name, _ in STAGES:
        n = sum(r.stage == name for r in ran)
        print('fuzz: stage %-15s %4d cases' % (name, n))
        if n == 0:
            missing.append(name)
    print('fuzz: wall time %.1f s, slowest case %.1f s' % (
        wall, max([r.seconds for r in ran] or [0.0])))

    failed_by = {p: [r for r in ran if p in r.problems] for p in PROPERTIES}
    passed = failed = 0
    for p in PROPERTIES:
        bad = failed_by[p]
        why = ''
        if p == 'stages' and missing and not single:
            why = 'never reached: ' + ', '.join(missing)
        if p == 'tally' and (len(invalid) + len(valid) + len(crashes) + len(hangs) != len(ran)
                             or len(clean2) != len(invalid) or len(valid_ok) != len(valid)):
            why = 'not every invalid variant exits 2 and every valid one 0 or 3, or the ' \
                  'counts do not add up'
        if bad:
            why = (why + '; ' if why else '') + '%d cases: %s' % (
                len(bad), ' '.join(r.case.ident for r in bad[:30]) + (' ...' if len(bad) > 30
                                                                      else ''))
        if why:
            failed += 1
            print('FAIL fuzz/%s: %s' % (p, why))
        else:
            passed += 1
            print('pass fuzz/%s' % p)
    print('%d passed, %d failed' % (passed, failed))
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
