#!/usr/bin/env python3
"""Checks of the user documentation (README.md, legacy/README.md, docs/*.md).

    python3 test/docs.py [path/to/flexmbs]

- every link and image points into the repository, at a file that exists,
  and at a heading that exists when it names one (no web address, nothing
  outside the repository, no developer notes that are not in it);
- the README stays a short entry point (at most 250 lines);
- docs/README.md lists every page of docs/;
- with the executable: docs/scene_reference.md is what
  `flexmbs scene-reference` prints from the schema, and the help names it;
  every command the documentation or `flexmbs --help` names has a usage of
  its own (`flexmbs COMMAND --help`: exit 0, `usage: flexmbs COMMAND`);
- with FLEXMBS_PKGCONFIG naming the folder of an installed flexmbs.pc (make
  test installs one first): docs/packaging.md gives the number of system
  libraries its link line names.

The last line is `N passed, M failed`; the exit status is non-zero on
failures.
"""
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MAX_README_LINES = 250
# notes of the developers that live outside the repository
OUTSIDE_NAMES = ('ALGORITHMS.md', 'PAPER.md', 'DESIGN.md', 'STYLE.md', '../shared')

LINK = re.compile(r'!?\[(?:[^\]\\]|\\.)*\]\(([^)\s]+)(?:\s+"[^"]*")?\)')
HEADING = re.compile(r'^(#{1,6})\s+(.*?)\s*#*\s*$')

passed = 0
failed = 0


def check(name, problems):
    global passed, failed
    if problems:
        failed += 1
        print('FAIL docs/%s: %s' % (name, '; '.join(problems[:10])
                                    + (' (and %d more)' % (len(problems) - 10)
                                       if len(problems) > 10 else '')))
    else:
        passed += 1
        print('pass docs/%s' % name)


def pages():
    found = [os.path.join(ROOT, 'README.md'), os.path.join(ROOT, 'legacy', 'README.md')]
    docs = os.path.join(ROOT, 'docs')
    found += sorted(os.path.join(docs, f) for f in os.listdir(docs) if f.endswith('.md'))
    return found


def outside_fences(text):
    """The lines of a Markdown text that are not in code blocks."""
    fence = False
    for line in text.split('\n'):
        if line.lstrip().startswith('```'):
            fence = not fence
            continue
        if not fence:
            yield line


def inside_fences(text):
    """The lines of a Markdown text that are in code blocks."""
    fence = False
    for line in text.split('\n'):
        if line.lstrip().startswith('```'):
            fence = not fence
        elif fence:
            yield line


# a command as the documentation writes it: in code, `flexmbs WORD`, or a
# line of a code block that starts with it (after a shell prompt)
CODE_COMMAND = re.compile(r'`flexmbs ([a-z][a-z-]*)')
BLOCK_COMMAND = re.compile(r'^\s*(?:\$ )?flexmbs ([a-z][a-z-]*)')
HELP_COMMAND = re.compile(r'^  flexmbs ([a-z][a-z-]*)', re.M)


def documented_commands(files):
    """The flexmbs commands the pages name, each with a page naming it."""
    found = {}
    for path in files:
        with open(path, encoding='utf-8') as f:
            text = f.read()
        names = set(CODE_COMMAND.findall(text))
        names.update(m.group(1) for m in map(BLOCK_COMMAND.match, inside_fences(text)) if m)
        for name in names:
            found.setdefault(name, os.path.relpath(path, ROOT))
    return found


def command_help_problems(exe, files, usage):
    """Each command named by the pages or the overview has its own usage."""
    named = documented_commands(files)
    for name in HELP_COMMAND.findall(usage):
        named.setdefault(name, '`flexmbs --help`')
    problems = []
    # `flexmbs help COMMAND` is the help itself, not a command: it must give
    # the command's usage, checked on one command
    if named.pop('help', None):
        run = subprocess.run([exe, 'help', 'run'], capture_output=True, text=True)
        if run.returncode != 0 or not run.stdout.startswith('usage: flexmbs run'):
            problems.append('`flexmbs help run` gives exit %d and %r'
                            % (run.returncode, (run.stderr or run.stdout)[:80]))
    for name, where in sorted(named.items()):
        run = subprocess.run([exe, name, '--help'], capture_output=True, text=True)
        if (run.returncode != 0 or run.stderr
                or not run.stdout.startswith('usage: flexmbs ' + name)):
            problems.append('%s names `flexmbs %s`, whose --help gives exit %d and %r'
                            % (where, name, run.returncode, (run.stderr or run.stdout)[:80]))
    if not named:
        problems.append('no command found in the pages')
    return problems


def slug(heading):
    """GitHub's anchor of a heading: lower case, markup and punctuation
    dropped, blanks as hyphens."""
    text = re.sub(r'`|\*|_(?=\W)|(?<=\W)_', '', heading).strip().lower()
    text = re.sub(r'[^\w\- ]', '', text)
    return text.replace(' ', '-')


def anchors(path):
    seen = {}
    result = set()
    with open(path, encoding='utf-8') as f:
        for line in outside_fences(f.read()):
            m = HEADING.match(line)
            if not m:
                continue
            base = slug(m.group(2))
            k = seen.get(base, 0)
            seen[base] = k + 1
            result.add(base if k == 0 else '%s-%d' % (base, k))
    return result


def link_problems(path):
    problems = []
    rel = os.path.relpath(path, ROOT)
    with open(path, encoding='utf-8') as f:
        text = f.read()
    for line in outside_fences(text):
        for target in LINK.findall(line):
            if re.match(r'^[a-z][a-z0-9+.-]*:', target, re.I):
                problems.append('%s: %s points outside the repository' % (rel, target))
                continue
            file_part, _, anchor = target.partition('#')
            goal = (os.path.normpath(os.path.join(os.path.dirname(path), file_part))
                    if file_part else path)
            if os.path.commonpath([ROOT, os.path.realpath(goal)]) != ROOT:
                problems.append('%s: %s leaves the repository' % (rel, target))
            elif not os.path.exists(goal):
                problems.append('%s: %s: no such file' % (rel, target))
            elif anchor and goal.endswith('.md') and anchor not in anchors(goal):
                problems.append('%s: %s: no such heading in %s'
                                % (rel, target, os.path.relpath(goal, ROOT)))
    for name in OUTSIDE_NAMES:
        if name in text:
            problems.append('%s names %s, which is not in the repository' % (rel, name))
    return problems


def main():
    files = pages()
    for path in files:
        check('links/' + os.path.relpath(path, ROOT), link_problems(path))

    with open(os.path.join(ROOT, 'README.md'), encoding='utf-8') as f:
        lines = f.read().count('\n')
    check('readme-short', [] if lines <= MAX_README_LINES else
          ['README.md has %d lines, more than %d' % (lines, MAX_README_LINES)])

    index = os.path.join(ROOT, 'docs', 'README.md')
    with open(index, encoding='utf-8') as f:
        listed = set(LINK.findall(f.read()))
    missing = [os.path.basename(p) for p in files
               if os.path.basename(os.path.dirname(p)) == 'docs' and p != index
               and os.path.basename(p) not in listed]
    check('index-lists-every-page', ['docs/README.md does not list ' + m for m in missing])

    if len(sys.argv) > 1:
        exe = sys.argv[1]
        run = subprocess.run([exe, 'scene-reference'], capture_output=True, text=True)
        with open(os.path.join(ROOT, 'docs', 'scene_reference.md'), encoding='utf-8') as f:
            page = f.read()
        problems = []
        if run.returncode != 0 or run.stderr:
            problems.append('exit %d, stderr %r' % (run.returncode, run.stderr))
        elif run.stdout != page:
            problems.append('docs/scene_reference.md differs from `flexmbs scene-reference`: '
                            'regenerate it with `flexmbs scene-reference > '
                            'docs/scene_reference.md`')
        check('scene-reference-generated', problems)
        usage = subprocess.run([exe, '--help'], capture_output=True, text=True).stdout
        check('help-names-the-reference', [] if 'docs/scene_reference.md' in usage
              else ['--help does not name docs/scene_reference.md'])
        check('every-command-has-its-help', command_help_problems(exe, files, usage))

    pc_dir = os.environ.get('FLEXMBS_PKGCONFIG')
    if pc_dir:
        check('packaging-library-count', library_count_problems(pc_dir))

    print('%d passed, %d failed' % (passed, failed))
    return 1 if failed else 0


def library_count_problems(pc_dir):
    """docs/packaging.md's 'followed by the N system libraries' against the
    -l flags of `pkg-config --libs flexmbs` in pc_dir."""
    env = dict(os.environ, PKG_CONFIG_PATH=pc_dir)
    run = subprocess.run(['pkg-config', '--libs', 'flexmbs'], capture_output=True, text=True,
                         env=env)
    if run.returncode != 0:
        return ['pkg-config --libs flexmbs in %s failed: %s' % (pc_dir, run.stderr.strip())]
    libraries = [w for w in run.stdout.split() if w.startswith('-l')]
    with open(os.path.join(ROOT, 'docs', 'packaging.md'), encoding='utf-8') as f:
        said = re.search(r'followed by the (\d+) system libraries', f.read())
    if not said:
        return ["docs/packaging.md no longer says 'followed by the N system libraries'"]
    if int(said.group(1)) != len(libraries):
        return ['docs/packaging.md says %s system libraries, pkg-config names %d'
                % (said.group(1), len(libraries))]
    return []


if __name__ == '__main__':
    sys.exit(main())
