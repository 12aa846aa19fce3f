#!/usr/bin/env python3
"""The architecture's rules, checked on the sources (run by `make test`).

- src/io/ reads and writes: it imports no solver module, and of the run
  layer only the catalogue's table of names (run/catalogue).
- A solver's name ('radau5', 'ddassl', 'ida', 'mexax') is written as a
  string only in the solver's own modules in src/dae/ (<solver>.f90 and
  the <solver>_*.f90 it is split into), in the catalogue
  (src/run/catalogue.f90) and in the scene schema (with the typed scene
  generated from it, src/io/scene_records.f90); everywhere else in
  src/, app/ and bench/ the code asks the catalogue by capability.
- bench/ and the command line build solvers through the catalogue's
  factories: bench/ uses no solver module's type.
- The types of src/mbs/ and src/fe/ keep their parts: src/run/ and src/io/
  reach into their data components (a reference chain that steps into a
  component, not a type-bound procedure, of such a type: test/reach_ins.py
  follows declarations, components, associate and select type names) at
  most REACH_IN_BOUND times, each with a comment saying why (issue 35).
- The scene schema's joint types (joint_choices) are those of the table
  of joint types (src/mbs/joint_types.f90).

Prints `pass layers/...` or `FAIL layers/...: why` lines and
`N passed, M failed` last; exits non-zero on failures.
"""
import os
import re
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from reach_ins import reach_ins, sources  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..')
SOLVERS = ('radau5', 'ddassl', 'ida', 'mexax')
SOLVER_MODULE = re.compile(r'^\s*use\s+flexmbs_dae_(radau5|ddassl|ida|mexax)\b', re.I)
RUN_MODULE = re.compile(r'^\s*use\s+(flexmbs_run_\w+)', re.I)
# (io/scene_records is generated from the schema's table: test/scene_records.py)
OWNERS = {'src/dae/radau5.f90', 'src/dae/ddassl.f90', 'src/dae/ida.f90',
          'src/dae/mexax.f90', 'src/run/catalogue.f90', 'src/io/scene_schema.f90',
          'src/io/scene_records.f90'}

passed = failed = 0


def report(name, problems):
    global passed, failed
    if problems:
        failed += 1
        print('FAIL layers/%s: %s' % (name, '; '.join(problems[:8]) +
                                      (' (+%d more)' % (len(problems) - 8)
                                       if len(problems) > 8 else '')))
    else:
        passed += 1
        print('pass layers/%s' % name)


def strings(line):
    """The character literals of a Fortran source line, comments left out
    (a continued literal's pieces count as separate strings)."""
    out, i, n = [], 0, len(line)
    while i < n:
        c = line[i]
        if c == '!':
            break
        if c in '\'"':
            j, text = i + 1, ''
            while j < n:
                if line[j] == c:
                    if j + 1 < n and line[j + 1] == c:
                        text += c
                        j += 2
                        continue
                    break
                text += line[j]
                j += 1
            out.append(text)
            i = j + 1
        else:
            i += 1
    return out


io_imports = []
for rel, path in sources('src/io'):
    for k, line in enumerate(open(path, encoding='utf-8'), 1):
        if SOLVER_MODULE.match(line):
            io_imports.append('%s:%d imports %s' % (rel, k, line.split()[1].rstrip(',')))
        m = RUN_MODULE.match(line)
        if m and m.group(1).lower() != 'flexmbs_run_catalogue':
            io_imports.append('%s:%d imports %s' % (rel, k, m.group(1)))
report('io-imports-no-solver-or-runner', io_imports)

named = []
word = re.compile(r'\b(%s)\b' % '|'.join(SOLVERS), re.I)
for rel, path in sources('src', 'app', 'bench'):
    if rel in OWNERS or re.match(r'src/dae/(%s)_\w+\.f90$' % '|'.join(SOLVERS), rel):
        continue
    for k, line in enumerate(open(path, encoding='utf-8'), 1):
        for text in strings(line):
            m = word.search(text)
            if m:
                named.append('%s:%d names %s in %r' % (rel, k, m.group(1), text[:60]))
report('solver-names-only-in-catalogue-schema-and-solvers', named)

bench_types = []
for rel, path in sources('bench'):
    for k, line in enumerate(open(path, encoding='utf-8'), 1):
        m = SOLVER_MODULE.match(line)
        if m and not re.search(r'only:\s*mexax_t\s*,\s*mexax_base_euler', line):
            bench_types.append('%s:%d imports %s' % (rel, k, line.split()[1].rstrip(',')))
report('bench-builds-solvers-from-the-catalogue', bench_types)

# The catalogue's names are the solvers' own.
names = {}
for s in SOLVERS:
    text = open(os.path.join(ROOT, 'src/dae/%s.f90' % s), encoding='utf-8').read()
    m = re.search(r'function\s+%s_name\b.*?name\s*=\s*\'(\w+)\'' % s, text, re.S | re.I)
    names[s] = m.group(1) if m else None
catalogue = open(os.path.join(ROOT, 'src/run/catalogue.f90'), encoding='utf-8').read()
listed = re.findall(r"solver_info_t\('(\w+)'", catalogue)
problems = ['%s_t%%name() is %r' % (s, names[s]) for s in SOLVERS if names[s] != s]
if sorted(listed) != sorted(SOLVERS):
    problems.append('the catalogue lists %s' % listed)
choices = re.search(r"solver_choices\s*=\s*'([^']*)'", catalogue)
if not choices or choices.group(1).split('|') != listed:
    problems.append('solver_choices %r differs from the table %s'
                    % (choices.group(1) if choices else None, listed))
pnames = re.findall(r"problem_info_t\('(\w+)'", catalogue)
pchoices = re.search(r"problem_choices\s*=\s*'([^']*)'", catalogue, re.S)
if not pchoices or re.sub(r"&\s*&", '', pchoices.group(1)).split('|') != pnames:
    problems.append('problem_choices differs from the table %s' % pnames)
report('catalogue-names-are-the-solvers-names', problems)

# Reach-ins from run/ and io/ into the components of mbs/ and fe/ types,
# following chains through components, associate and select type names
# (test/reach_ins.py). 0: the outer layers ask the formulation's blocks and
# the system's, chains', markers' and bodies' bindings (issue 35, part 3);
# a new reach-in fails
REACH_IN_BOUND = 0

# the counter's own check: a sample with each kind of chain it follows
SAMPLE = """subroutine sample(plan, sys)
    type(run_plan_t), intent(in) :: plan
    type(mbs_system_t), pointer :: sys
    select type (m => plan%mechanical)
    type is (mbs_system_t)
        n = size(m%chains)
        associate (c => m%chains(1))
            k = c%nq + c%link_count()
            x = c%bodies(1)%centre
        end associate
    end select
    n = sys%joint_count() + sys%joints(1)%joint%kind
end subroutine sample
"""
EXPECTED = ['mbs_system_t%chains', 'mbs_system_t%chains', 'rigid_chain_t%bodies',
            'chain_body_t%centre', 'mbs_system_t%joints', 'assembled_joint_t%joint',
            'joint_t%kind']
with tempfile.TemporaryDirectory() as folder:
    with open(os.path.join(folder, 'sample.f90'), 'w', encoding='utf-8') as f:
        f.write(SAMPLE)
    seen = [r.split()[1] for r in reach_ins(outer=(folder,))]
report('reach-in-counter-follows-chains',
       [] if seen == EXPECTED else ['found %s, expected %s' % (seen, EXPECTED)])

found = reach_ins()
print('    %d reach-ins from run/ and io/ into mbs/ and fe/ components (bound %d)'
      % (len(found), REACH_IN_BOUND))
report('run-and-io-keep-out-of-mbs-and-fe-components',
       [] if len(found) <= REACH_IN_BOUND else
       ['%d reach-ins, more than %d: %s' % (len(found), REACH_IN_BOUND, r) for r in found])

# The scene's joint types are the table's: joint_choices lists, in order,
# the entries of flexmbs_mbs_joint_types that have primitives of their own.
table = open(os.path.join(ROOT, 'src/mbs/joint_types.f90'), encoding='utf-8').read()
jnames = re.findall(r"joint_type_t\('(\w+)',\s*\[", table)
jchoices = re.search(r"joint_choices\s*=\s*&?\s*'([^']*)'", table)
problems = []
if not jnames:
    problems.append('no joint types found in src/mbs/joint_types.f90')
if not jchoices or jchoices.group(1).split('|') != jnames:
    problems.append('joint_choices %r differs from the table %s'
                    % (jchoices.group(1) if jchoices else None, jnames))
report('joint-choices-are-the-joint-table', problems)

print('%d passed, %d failed' % (passed, failed))
sys.exit(1 if failed else 0)
