#!/usr/bin/env python3
"""The typed scene follows from the scene schema: src/io/scene_records.f90
is generated from the table in src/io/scene_schema.f90 by this script.

    python3 test/scene_records.py           check that the file is current
    python3 test/scene_records.py --write   write it anew

For every group of the schema (the study's aside, read by io/study_file) it
writes a record type with a component per variable, of the variable's kind
and count, initialised to the schema's default, and the group's reader:
each variable from its entry or, when not given, from the schema's default
(io/scene_values' get), a choice in lower case. &simulation, &solver and
&output share one record (the scene's own), in which &solver's `name` is
`solver_name`; the solvers' own settings (the &solver variables without a
default) are not components: the reader hands them to the solver by name
(io/scene_reader, dae/solver_setting). io/scene_input extends the records
with what the reader derives (lines, names by position, resolved paths).

`make test` runs the check: the last line is `N passed, M failed`, the exit
status non-zero on failure (a schema changed without regenerating the file).
"""
import os
import re
import sys

WIDTH = 100
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCHEMA = os.path.join(ROOT, 'src', 'io', 'scene_schema.f90')
TARGET = os.path.join(ROOT, 'src', 'io', 'scene_records.f90')

# groups read elsewhere, and why
LEFT_OUT = {'study': 'io/study_file reads its lists as given, not padded'}
# the groups of the scene's own record, in this order
SCENE_GROUPS = ('simulation', 'solver', 'output')
RENAMED = {('solver', 'name'): 'solver_name'}
# strings compared case-insensitively without a list of choices in the
# schema (io/scene_checks checks them against the library's own list)
LOWER_CASE = {('solver', 'linear_solver')}


def string_lengths():
    """{variable name: declared length} from the schema's string_length."""
    source = open(SCHEMA, encoding='utf-8').read()
    body = source[source.index('function string_length'):]
    body = body[:body.index('end function string_length')]
    lengths = {}
    for names, length in re.findall(r"case\s*\(([^)]*)\)\s*;?\s*(?:&\s*\n)?\s*"
                                    r"string_length\s*=\s*(\w+)", body):
        for name in re.findall(r"'(\w+)'", names):
            lengths[name] = length
    return lengths


STRING_LENGTH = string_lengths()


def fortran_strings(text):
    """The value of a Fortran character expression made of literals joined
    by // (a named constant stands as '<name>')."""
    out, i = '', 0
    while i < len(text):
        c = text[i]
        if c in '\'"':
            j = i + 1
            while j < len(text):
                if text[j] == c:
                    if j + 1 < len(text) and text[j + 1] == c:
                        out += c
                        j += 2
                        continue
                    break
                out += text[j]
                j += 1
            i = j + 1
        elif c.isalpha():
            m = re.match(r'\w+', text[i:])
            out += '<%s>' % m.group(0)
            i += len(m.group(0))
        else:
            i += 1
    return out


def nesting(text, start=0):
    """(index, character, depth) of the characters of `text` from `start`
    outside character literals, depth counting the open parentheses."""
    depth, quote = 0, None
    for i in range(start, len(text)):
        c = text[i]
        if quote or c in '\'"':
            quote = None if c == quote else (quote or c)
            continue
        depth += (c == '(') - (c == ')')
        yield i, c, depth


def split_top(text):
    """Arguments of a call: split at commas outside quotes and parentheses."""
    cuts = [i for i, c, depth in nesting(text) if c == ',' and depth == 0]
    bounds = [-1] + cuts + [len(text)]
    return [text[a + 1:b].strip() for a, b in zip(bounds, bounds[1:])]


def schema_entries():
    """The schema's variables: dicts of group, name, kind, count, list,
    default, choices, unit, doc."""
    source = open(SCHEMA, encoding='utf-8').read()
    body = source[source.index('schema(*) = ['):]
    # continuation lines: '&' at a line's end (and inside a literal, '&'
    # again at the next line's start)
    body = re.sub(r'&[ \t]*\n[ \t]*&', '', body)
    body = re.sub(r'&[ \t]*\n[ \t]*', ' ', body)
    entries = []
    for m in re.finditer(r'var_spec_t\(', body):
        # the call ends where its opening parenthesis closes
        i = next(i for i, c, depth in nesting(body, m.end() - 1) if depth == 0)
        args = split_top(body[m.end():i])
        spec = {'count': '1', 'list': False, 'default': '', 'choices': '', 'unit': '',
                'doc': ''}
        positional = ['group', 'name', 'kind', 'count', 'list']
        for k, arg in enumerate(args):
            key, _, value = arg.partition('=')
            if _ and re.fullmatch(r'\s*\w+\s*', key) and not arg.startswith("'"):
                key = key.strip()
            else:
                key, value = positional[k], arg
            value = value.strip()
            if key in ('group', 'name', 'default', 'choices', 'unit', 'doc', 'rule'):
                spec[key] = fortran_strings(value)
            elif key == 'list':
                spec[key] = value.lower() == '.true.'
            else:
                spec[key] = value
        entries.append(spec)
        if body[i + 1:].lstrip().startswith(']'):
            break
    return entries


def own_setting(v):
    return v['group'] == 'solver' and not v['default']


def component_name(v):
    return RENAMED.get((v['group'], v['name']), v['name'])


def literal(v, text):
    """The schema's default text as a Fortran constant of the variable's kind."""
    kind = v['kind']
    if kind == 'kind_string':
        return "'%s'" % text.replace("'", "''")
    if kind == 'kind_logical':
        return text
    values = [t.strip() for t in text.split(',')]
    if kind == 'kind_real':
        values = [(t if re.search(r'[.eEdD]', t) else t + '.0') + '_wp' for t in values]
    if v['count'] != '1':
        return '[' + ', '.join(values) + ']'
    return values[0]


def declaration(v):
    kind = {'kind_real': 'real(wp)', 'kind_integer': 'integer', 'kind_logical': 'logical',
            'kind_string': 'character(len=%s)' % STRING_LENGTH.get(v['name'], 'len_name')}
    head = kind[v['kind']]
    name = component_name(v)
    if v['list']:
        head += ', allocatable'
        name += '(:)'
    elif v['count'] != '1':
        name += '(%s)' % v['count']
    if v['default'] and not v['list']:
        name += ' = ' + literal(v, v['default'])
    elif v['kind'] == 'kind_string' and not v['list']:
        name += " = ''"
    # led by its group: FORD would take a leading 'word:' for a metadata key
    doc = '&%s: %s' % (v['group'], v['doc'])
    if v['unit']:
        doc += ' [%s]' % v['unit']
    line = '        %s :: %s' % (head, name)
    if len(line) + len(doc) + 4 <= WIDTH:
        return line + ' !! ' + doc
    return '\n'.join(wrapped(doc, '        !> ')) + '\n' + line


def wrapped(text, prefix):
    """`text` in lines of at most WIDTH characters, each led by `prefix`."""
    lines, line = [], ''
    for word in text.split():
        if line and len(prefix) + len(line) + 1 + len(word) > WIDTH:
            lines.append(prefix + line)
            line = word
        else:
            line = line + ' ' + word if line else word
    return lines + [prefix + line]


def name_list(head, names):
    """A declaration `head` followed by `names`, continued with & at WIDTH."""
    lines, line = [], head
    for k, name in enumerate(names):
        piece = name + (',' if k < len(names) - 1 else '')
        if len(line) + 1 + len(piece) + 2 > WIDTH:
            lines.append(line + ' &')
            line = '        ' + piece
        else:
            line = line + ' ' + piece if not line.endswith(':') else line + ' ' + piece
    return lines + [line]


def reads(v, instance):
    """The reader's lines for one variable; `instance` the argument's text."""
    group, name = v['group'], v['name']
    target = 'r%' + component_name(v)
    if v['list']:
        return ["        call get_list(e, '%s', '%s', %s)" % (group, name, target)]
    call = "        call get(e, '%s', '%s', %s%s)" % (group, name, target, instance)
    lines = [call if len(call) <= 100 else
             "        call get(e, '%s', '%s', &\n            %s%s)" % (group, name, target,
                                                                    instance)]
    if v['kind'] == 'kind_string' and (v['choices'] or (group, name) in LOWER_CASE):
        lines.append('        %s = lower(%s)' % (target, target))
    return lines


def generate():
    entries = [v for v in schema_entries() if v['group'] not in LEFT_OUT]
    groups = []
    for v in entries:
        if v['group'] not in groups:
            groups.append(v['group'])
    records = [('scene', list(SCENE_GROUPS))] + \
        [(g, [g]) for g in groups if g not in SCENE_GROUPS]
    used = set()
    for v in entries:
        for name in re.findall(r'\b(len_\w+|max_\w+)\b', v['count'] + ' ' +
                               STRING_LENGTH.get(v['name'], 'len_name')):
            used.add(name)
    out = ['! GENERATED by test/scene_records.py from the table of io/scene_schema:',
           '! do not edit; after changing the schema run `python3 test/scene_records.py',
           '! --write` (make test checks that this file is current).',
           '',
           '!> The typed scene as the schema declares it: a record type per group of',
           '!> the scene schema (&simulation, &solver and &output share the scene\'s',
           '!> own), a component per variable, initialised to its default, and the',
           '!> group\'s reader: each variable from its entry or, when not given, from',
           '!> the schema\'s default, a choice in lower case. The solvers\' own settings',
           '!> are read by name (io/scene_reader); io/scene_input extends the records.',
           'module flexmbs_io_scene_records',
           '    use flexmbs_core_kinds, only: wp',
           '    use flexmbs_core_text, only: lower',
           *name_list('    use flexmbs_io_scene_schema, only:', sorted(used)),
           '    use flexmbs_io_scene_lexer, only: entry_t',
           '    use flexmbs_io_scene_values, only: get, get_list',
           '    implicit none',
           '    private',
           '',
           *name_list('    public ::', ['read_%s_record' % r for r, _ in records]),
           '']
    for record, members in records:
        out.append('    !> ' + ', '.join('&' + g for g in members) + '.')
        out.append('    type, public :: %s_record_t' % record)
        for g in members:
            if len(members) > 1:
                out.append('        ! &' + g)
            out += [declaration(v) for v in entries if v['group'] == g and not own_setting(v)]
        out += ['    end type %s_record_t' % record, '']
    out += ['contains', '']
    for k, (record, members) in enumerate(records):
        repeatable = record not in ('scene', 'multibody')
        instance = ', instance' if repeatable else ''
        out.append('    !> ' + ', '.join('&' + g for g in members) +
                   (' (occurrence `instance`)' if repeatable else '') + ' from `e`.')
        out.append('    subroutine read_%s_record(e, r%s)' % (record, instance))
        out.append('        type(entry_t), intent(in) :: e(:)')
        out.append('        type(%s_record_t), intent(inout) :: r' % record)
        if repeatable:
            out.append('        integer, intent(in) :: instance')
        for g in members:
            for v in entries:
                if v['group'] == g and not own_setting(v):
                    out += reads(v, instance)
        out.append('    end subroutine read_%s_record' % record)
        if k < len(records) - 1:
            out.append('')
    out.append('end module flexmbs_io_scene_records')
    return '\n'.join(out) + '\n'


def main():
    text = generate()
    if '--write' in sys.argv[1:]:
        with open(TARGET, 'w', encoding='utf-8') as f:
            f.write(text)
        print('wrote %s' % os.path.relpath(TARGET, ROOT))
        return 0
    current = open(TARGET, encoding='utf-8').read() if os.path.exists(TARGET) else ''
    if current == text:
        print('pass scene-records/generated-from-the-schema')
        print('1 passed, 0 failed')
        return 0
    print('FAIL scene-records/generated-from-the-schema: src/io/scene_records.f90 differs '
          'from what the schema gives: run python3 test/scene_records.py --write')
    print('0 passed, 1 failed')
    return 1


if __name__ == '__main__':
    sys.exit(main())
