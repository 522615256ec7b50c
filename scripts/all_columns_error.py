#!/usr/bin/env python3
"""Every example's error in every column against a tight reference, and
whether the summary's global error estimate warns of it.

`scripts/direct_global_error.py` judges runs by the models' `exact` lines,
which cover a few columns only (a ball on a turntable's exact lines give
x', y', not its Euler angles' rates, where its error is). This script takes
as reference direct integration at rtol 1e-13 (checked against the field at
1e-13: `refdiff`) and measures max |a - b| / max(|b|, 1) over every column
and 201 samples.

    python3 scripts/all_columns_error.py --lagc LAGC --method field --json OUT [FILES...]
    python3 scripts/all_columns_error.py --compare A.json B.json

A run is a silent miss when its error passes 10·rtol and its estimate does
not, a false warning the other way round.
"""
import argparse, glob, hashlib, json, os, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(lagc, f, method, rtol, out, samples):
    p = subprocess.run([lagc, 'run', f, '--method', method, '--rtol', rtol,
                        '--atol', '%g' % (float(rtol) / 100), '--samples', samples,
                        '-o', out, '--summary', 'json'], capture_output=True, text=True)
    js = [x for x in p.stderr.splitlines() if x.startswith('{')]
    if p.returncode != 0 or not js:
        return None
    return json.loads(js[-1])


def load(path):
    lines = open(path).read().split('\n')
    return [list(map(float, x.split(','))) for x in lines[1:] if x]


def diff(a, b):
    return max((abs(x - y) / max(abs(y), 1) for ra, rb in zip(a, b)
                for x, y in zip(ra[1:], rb[1:])), default=0.0)


def kind(r, rtol):
    if r.get('fail'):
        return 'fail'
    over, warned = r['err'] > 10 * rtol, (r['est'] or 0) > 10 * rtol
    return 'SILENT' if over and not warned else 'false-warn' if warned and not over else 'ok'


def compare(a_path, b_path):
    a, b = json.load(open(a_path)), json.load(open(b_path))
    counts = {}
    for k in sorted(a):
        if k not in b:
            continue
        rtol = float(k.split()[1])
        ka, kb = kind(a[k], rtol), kind(b[k], rtol)
        for side, c in (('A', ka), ('B', kb)):
            counts[(side, c)] = counts.get((side, c), 0) + 1
        if ka != 'ok' or kb != 'ok':
            show = lambda r: 'fail' if r.get('fail') else \
                f"err {r['err'] / rtol:8.3g} est {(r['est'] or 0) / rtol:8.3g} evals {r['evals']}"
            print(f'{k:40s} {ka:10s} {show(a[k])} | {kb:10s} {show(b[k])}')
    print(sorted(counts.items()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('files', nargs='*')
    ap.add_argument('--lagc')
    ap.add_argument('--reference-lagc', help='lagc for the references (default --lagc)')
    ap.add_argument('--method', default='field')
    ap.add_argument('--rtols', default='1e-6,1e-8,1e-10,1e-12')
    ap.add_argument('--samples', default='201')
    ap.add_argument('--json')
    ap.add_argument('--cache', default=os.path.join(tempfile.gettempdir(), 'lagc-all-columns'))
    ap.add_argument('--compare', nargs=2, metavar=('A', 'B'))
    args = ap.parse_args()
    if args.compare:
        return compare(*args.compare)
    ref_lagc = args.reference_lagc or args.lagc
    os.makedirs(args.cache, exist_ok=True)
    results = {}
    # The run's output, one file a process: scans sharing a cache ran
    # at once and read each other's runs.
    out = os.path.join(args.cache, f'run-{os.getpid()}.csv')
    for f in args.files or sorted(glob.glob(os.path.join(ROOT, 'examples', '*.lag'))):
        name = os.path.basename(f)[:-4]
        key = hashlib.md5((os.path.abspath(f) + args.samples).encode()).hexdigest()[:10]
        ref, ref_field = (os.path.join(args.cache, f'{name}-{key}{s}.csv') for s in ('', '-field'))
        if not os.path.exists(ref):
            if run(ref_lagc, f, 'direct', '1e-13', ref, args.samples) is None:
                print(name, 'reference failed')
                continue
            run(ref_lagc, f, 'field', '1e-13', ref_field, args.samples)
        reference = load(ref)
        refdiff = diff(load(ref_field), reference) if os.path.exists(ref_field) else None
        for rtol in args.rtols.split(','):
            s = run(args.lagc, f, args.method, rtol, out, args.samples)
            if s is None:
                results[f'{name} {rtol}'] = {'fail': True}
                continue
            err = diff(load(out), reference)
            est = s.get('global_error_estimate')
            results[f'{name} {rtol}'] = dict(err=err, est=est, evals=s.get('rhs_evaluations'), refdiff=refdiff)
            r = float(rtol)
            print(f'{name:34s} {rtol:6s} error {err / r:9.3g} rtol, estimate {(est or 0) / r:9.3g} rtol, '
                  f'{kind(results[f"{name} {rtol}"], r)} (reference to field 1e-13: {refdiff})', flush=True)
    if args.json:
        json.dump(results, open(args.json, 'w'), indent=1)


if __name__ == '__main__':
    sys.exit(main())
