#!/usr/bin/env python3
"""The error of the output between steps against the error at the steps'
ends, every column, both methods (issue 29; docs/BENCHMARKS.md §10p).

Builds each model's crate with `LAGC build --runtime DIR/rt`, patches that
runtime copy to print the integrator's step ends (`STEPEND t` on stderr,
from `Solver::step_ends` after every advance: the field's window gives
its steps' ends), and builds the crates in DIR/tgt. Then for every model,
method and rtol (atol rtol/100):

  samples: the run at --samples N (the continuous extension between steps)
  ends:    the same run at --times <its step ends> (output times never
           change the steps: the rows are the steps' own states)

each against direct integration at rtol 1e-13 stepped onto the same times
(`--step-to-times`), as max |a - b| / max(|b|, 1) over columns and rows.

    python3 scripts/between_steps_errors.py --lagc LAGC --dir DIR [--runtime-src RT] [--json OUT] MODEL...
"""
import argparse, json, os, re, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PATCH_AT = '        self.progress.update(solver.time());\n'
PATCH = PATCH_AT + ('        // MEASUREMENT ONLY: the step ends.\n        {\n'
                    '            let mut ends = Vec::new();\n'
                    '            solver.step_ends(&mut ends);\n'
                    '            for e in ends {\n                eprintln!("STEPEND {e:e}");\n            }\n'
                    '        }\n')


def model_file(name):
    for p in (f'examples/{name}.lag', f'tests/data/{name}.lag', f'benches/data/{name}.lag',
              f'tests/data/mass_law_forms/{name}.lag'):
        if os.path.exists(os.path.join(ROOT, p)):
            return os.path.join(ROOT, p)
    raise SystemExit(f'no model {name}')


def build(lagc, d, names, runtime_src=None):
    rt = os.path.join(d, 'rt')
    for n in names:
        subprocess.run([lagc, 'build', model_file(n), '-o', os.path.join(d, 'crates', n),
                        '--runtime', rt, '--force'], check=True, capture_output=True)
    if runtime_src:
        # Another runtime's sources (a branch's, against LAGC's generated
        # code): its files over the copy LAGC wrote.
        subprocess.run(['cp', '-r', os.path.join(runtime_src, 'src', '.'), os.path.join(rt, 'src')],
                       check=True)
    p = os.path.join(rt, 'src', 'run', 'integration.rs')
    s = open(p).read()
    if 'STEPEND' not in s:
        assert s.count(PATCH_AT) == 1, 'the patch point moved'
        open(p, 'w').write(s.replace(PATCH_AT, PATCH))
    env = dict(os.environ, CARGO_TARGET_DIR=os.path.abspath(os.path.join(d, 'tgt')))
    for n in names:
        subprocess.run(['cargo', 'build', '--release', '-q'], cwd=os.path.join(d, 'crates', n),
                       env=env, check=True)


def run(binary, args):
    p = subprocess.run([binary, *args, '--summary', 'json'], capture_output=True, text=True)
    ends = [float(x.split()[1]) for x in p.stderr.splitlines() if x.startswith('STEPEND')]
    js = [x for x in p.stderr.splitlines() if x.startswith('{')]
    rows = [list(map(float, x.split(','))) for x in p.stdout.split('\n')[1:] if x]
    if p.returncode != 0 or not js:
        return None
    return rows, ends, json.loads(js[-1])


def err(a, b):
    return max((max(abs(x - y) / max(abs(y), 1) for x, y in zip(ra[1:], rb[1:]))
                for ra, rb in zip(a, b)), default=0.0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('models', nargs='+')
    ap.add_argument('--lagc', required=True)
    ap.add_argument('--dir', required=True)
    ap.add_argument('--methods', default='field,direct')
    ap.add_argument('--rtols', default='1e-6,1e-8,1e-10,1e-12')
    ap.add_argument('--samples', default='1001')
    ap.add_argument('--no-build', action='store_true')
    ap.add_argument('--runtime-src', help="a runtime's directory whose src/ replaces LAGC's")
    ap.add_argument('--json')
    a = ap.parse_args()
    if not a.no_build:
        build(a.lagc, a.dir, a.models, a.runtime_src)
    results = {}
    for n in a.models:
        b = os.path.join(a.dir, 'tgt', 'release', 'lag-' + n.replace('_', '-'))
        ref = run(b, ['--method', 'direct', '--rtol', '1e-13', '--atol', '1e-15', '--step-to-times',
                      '--samples', a.samples])
        if ref is None:
            print(n, 'reference failed')
            continue
        for m in a.methods.split(','):
            for r in a.rtols.split(','):
                opts = ['--method', m, '--rtol', r, '--atol', '%g' % (float(r) / 100)]
                s = run(b, opts + ['--samples', a.samples])
                if s is None:
                    print(f'{n:28s} {m:6s} {r:6s} failed')
                    continue
                ends = sorted(set(s[1]))
                # A command line holds some thousands of times: past that,
                # every k-th step end (the largest error over them is then
                # a lower bound of the steps' ends' largest).
                k = -(-len(ends) // 3000)
                ends = ends[::k] + ([ends[-1]] if (len(ends) - 1) % k else [])
                times = ','.join(repr(t) for t in ends)
                e = run(b, opts + ['--times', times])
                re_ = run(b, ['--method', 'direct', '--rtol', '1e-13', '--atol', '1e-15',
                              '--step-to-times', '--times', times])
                if e is None or re_ is None or len(e[0]) != len(re_[0]):
                    print(f'{n:28s} {m:6s} {r:6s} step-end run failed')
                    continue
                es, ee = err(s[0], ref[0]), err(e[0], re_[0])
                est = s[2].get('global_error_estimate')
                rt = float(r)
                results[f'{n} {m} {r}'] = dict(samples=es, ends=ee, estimate=est, steps=len(s[1]),
                                                evals=s[2].get('rhs_evaluations'), method=s[2].get('method'))
                flag = 'MISS' if es > 10 * rt and (est or 0) <= 10 * rt else ''
                print(f'{n:28s} {m:6s} {r:6s} samples {es / rt:9.3g} ends {ee / rt:9.3g} '
                      f'ratio {es / max(ee, 1e-300):8.3g} est {(est or 0) / rt:8.3g} (rtol) '
                      f'steps {len(set(s[1])):6d} {flag}', flush=True)
    if a.json:
        json.dump(results, open(a.json, 'w'), indent=1)


if __name__ == '__main__':
    sys.exit(main())
