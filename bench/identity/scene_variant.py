#!/usr/bin/env python3
"""scene_variant.py SCENE OUT.nml RUNNAME T_END SOLVER [key=value ...]: a copy
of SCENE cut to T_END, run by SOLVER, writing RUNNAME.h5 (no ParaView files,
no table); key=value settings replace the scene's in &solver (solver keys)
or &output (every_step, n_output). For bench/identity/grid.sh."""
import re, sys
scene, out, run, t_end, solver = sys.argv[1:6]
extra = [a.split('=', 1) for a in sys.argv[6:]]
output_keys = {'every_step', 'n_output'}
text = open(scene).read().splitlines()
res = []
group = None
for line in text:
    s = line.strip()
    m = re.match(r'&(\w+)', s)
    if m:
        group = m.group(1).lower()
    drop = False
    for k, v in extra:
        if re.match(r'^\s*%s\s*=' % k, line) and group in ('solver', 'output'):
            drop = True
    if drop:
        continue
    line = re.sub(r'^(\s*t_end\s*=\s*)[0-9.eEdD+-]+', r'\g<1>' + t_end, line)
    line = re.sub(r'(,\s*t_end\s*=\s*)[0-9.eEdD+-]+', r'\g<1>' + t_end, line)
    if group == 'solver':
        line = re.sub(r"^(\s*name\s*=\s*)'radau5'", r"\g<1>'%s'" % solver, line)
    if s.lower().startswith('&output'):
        add = ", ".join("%s = %s" % (k, v) for k, v in extra if k in output_keys)
        line = "&output file = '%s.h5', vtk = '', table = '',%s" % (run, (' ' + add + ',') if add else '') + line.strip()[len('&output'):]
    if s.lower().startswith('&solver'):
        add = ", ".join("%s = %s" % (k, v) for k, v in extra if k not in output_keys)
        if add:
            line = "&solver " + add + "," + line.strip()[len('&solver'):]
    res.append(line)
open(out, 'w').write("\n".join(res) + "\n")
