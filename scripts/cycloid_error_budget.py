#!/usr/bin/env python3
"""The bead on a cycloid by direct integration against its closed form: which
column is off, at the samples and at the step ends, and the error budget of
the rolling angle's steps in the oscillator's own coordinates (issue 29;
docs/BENCHMARKS.md §10y).

The tautochrone is harmonic in its arc length s = 4 r sin(th/2):
s'' = -w² s, w = sqrt(g / (4 r)). Every step's local error is measured in
(s, s'/w) against the exact flow from the step's start (the (th, th')
subsystem of examples/bead_on_cycloid.lag is closed: th'' depends on th and
th' alone), and carried to the end by the flow, a rotation: the carried sum
is the global error at the end, exactly.

Setup, in DIR: the example's crate and a one-coordinate model of the same
motion in th alone (written here) built by LAGC with one runtime copy
DIR/rt, patched by scripts/cycloid_error_budget.patch (MEASUREMENT ONLY:
LAGC_SCRATCH_ENDS prints the step ends, LAGC_SCRATCH_NOPROJ turns the
keeper's projections off, LAGC_SCRATCH_PART partitions every mode), built in
DIR/tgt. Then for every variant and rtol (atol rtol/100, 201 samples):

    python3 scripts/cycloid_error_budget.py --lagc LAGC --dir DIR [--rtols 1e-6,...]

Error: max |a - b| / max(|b|, 1) per column, in rtol; est: the summary's
global_error_estimate in rtol.
"""
import argparse, json, math, os, shutil, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
R_, G, TH0 = 0.5, 9.81, 2.0
W = math.sqrt(G / (4 * R_))
S0 = math.sin(TH0 / 2)
NAMES = ['th', 'x', 'y', "th'", "x'", "y'"]
ANGLE = """// the bead on the cycloid in its rolling angle alone (scripts/cycloid_error_budget.py)
param r = 0.5;
param g = 9.81;
param th0 = 2;
coord th;
lagrangian = r^2 * th'^2 * (1 + cos(th)) - g * r * (1 - cos(th));
initial th = th0, th' = 0;
time 0 .. 20;
"""


def exact(t):
    u, du = S0 * math.cos(W * t), -S0 * W * math.sin(W * t)
    th, thd = 2 * math.asin(u), 2 * du / math.sqrt(1 - u * u)
    return [th, R_ * (th + math.sin(th)), R_ * (1 - math.cos(th)), thd,
            R_ * (1 + math.cos(th)) * thd, R_ * math.sin(th) * thd]


def to_s(th, thd):
    return 4 * R_ * math.sin(th / 2), 2 * R_ * math.cos(th / 2) * thd / W


def rotate(s, v, dt):
    return s * math.cos(W * dt) + v * math.sin(W * dt), -s * math.sin(W * dt) + v * math.cos(W * dt)


def build(lagc, d):
    rt = os.path.join(d, 'rt')
    # A fresh runtime copy every time, patched once.
    shutil.rmtree(rt, ignore_errors=True)
    open(os.path.join(d, 'cycloid_angle.lag'), 'w').write(ANGLE)
    for name, src in [('cycloid', os.path.join(ROOT, 'examples/bead_on_cycloid.lag')),
                      ('angle', os.path.join(d, 'cycloid_angle.lag'))]:
        out = os.path.join(d, name)
        shutil.rmtree(out, ignore_errors=True)
        subprocess.run([lagc, 'build', src, '-o', out, '--runtime', rt, '--force'],
                       check=True, capture_output=True)
    subprocess.run(['patch', '-p2', '-d', rt, '-i',
                    os.path.join(ROOT, 'scripts/cycloid_error_budget.patch')], check=True)
    for name in ['cycloid', 'angle']:
        subprocess.run(['cargo', 'build', '--release', '--quiet'], cwd=os.path.join(d, name),
                       env=dict(os.environ, CARGO_TARGET_DIR=os.path.join(d, 'tgt')), check=True)
    return (os.path.join(d, 'tgt/release/lag-bead-on-cycloid'),
            os.path.join(d, 'tgt/release/lag-cycloid-angle'))


def run(binary, rtol, extra, env):
    out = binary + '.csv'
    p = subprocess.run([binary, '--method', 'direct', '--rtol', rtol, '--atol',
                        '%g' % (float(rtol) / 100), '-o', out, '--summary', 'json', *extra],
                       capture_output=True, text=True, env=env)
    summary = json.loads([x for x in p.stderr.splitlines() if x.startswith('{')][-1])
    rows = [list(map(float, x.split(','))) for x in open(out).read().split('\n')[1:] if x]
    ends = [x.split()[1] for x in p.stderr.splitlines() if x.startswith('STEPEND')]
    return summary, rows, ends


def errors(rows, columns):
    per = [0.0] * len(columns)
    for row in rows:
        e = exact(row[0])
        for k, i in enumerate(columns):
            per[k] = max(per[k], abs(row[1 + k] - e[i]) / max(abs(e[i]), 1))
    return per


def measure(binary, columns, rtol, variant):
    env = dict(os.environ, LAGC_SCRATCH_ENDS='1')
    if variant != 'normals':
        env['LAGC_SCRATCH_' + variant.upper()] = '1'
    R = float(rtol)
    summary, rows, ends = run(binary, rtol, ['--samples', '201'], env)
    _, at_ends, _ = run(binary, rtol, ['--times', '0,' + ','.join(ends)], env)
    th, thd = columns.index(0), columns.index(3)
    carried, total = [0.0, 0.0], 0.0
    end = at_ends[-1][0]
    for a, b in zip(at_ends, at_ends[1:]):
        s_a = to_s(a[1 + th], a[1 + thd])
        s_b = to_s(b[1 + th], b[1 + thd])
        flow = rotate(*s_a, b[0] - a[0])
        local = (s_b[0] - flow[0], s_b[1] - flow[1])
        total += math.hypot(*local)
        c = rotate(*local, end - b[0])
        carried = [carried[0] + c[0], carried[1] + c[1]]
    exact_end = to_s(*[exact(end)[i] for i in (0, 3)])
    run_end = to_s(at_ends[-1][1 + th], at_ends[-1][1 + thd])
    return {
        'global_at_end': math.hypot(run_end[0] - exact_end[0], run_end[1] - exact_end[1]) / R,
        'samples': [e / R for e in errors(rows, columns)],
        'ends': [e / R for e in errors(at_ends, columns)],
        'estimate': summary['global_error_estimate'] / R,
        'steps': summary['steps'], 'projections': summary.get('projections'),
        'local_sum': total / R, 'carried': math.hypot(*carried) / R,
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--lagc', required=True)
    ap.add_argument('--dir', required=True)
    ap.add_argument('--rtols', default='1e-6,1e-7,1e-8,1e-9,1e-10,1e-11,1e-12')
    ap.add_argument('--json')
    a = ap.parse_args()
    os.makedirs(a.dir, exist_ok=True)
    cycloid, angle = build(os.path.abspath(a.lagc), os.path.abspath(a.dir))
    results = {}
    for label, binary, columns, variants in [
            ('cycloid', cycloid, list(range(6)), ['normals', 'noproj', 'part']),
            ('angle', angle, [0, 3], ['normals'])]:
        for variant in variants:
            for rtol in a.rtols.split(','):
                m = measure(binary, columns, rtol, variant)
                results[f'{label} {variant} {rtol}'] = m
                names = [NAMES[i] for i in columns]
                print(f'{label:7} {variant:7} {rtol:>6} error {max(m["samples"]):6.2f} '
                      f'(step ends {max(m["ends"]):6.2f}) est {m["estimate"]:6.2f} '
                      f'steps {m["steps"]:4} | s-space: local sum {m["local_sum"]:5.2f} '
                      f'carried {m["carried"]:5.2f} (global at the end {m["global_at_end"]:5.2f}) | ' +
                      ' '.join(f'{n} {v:.2f}' for n, v in zip(names, m['samples'])), flush=True)
    if a.json:
        json.dump(results, open(a.json, 'w'), indent=1)


if __name__ == '__main__':
    sys.exit(main())
