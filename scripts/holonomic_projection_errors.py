#!/usr/bin/env python3
"""The holonomic examples' errors, every column, by both methods at rtol 1e-6 … 1e-12,
for one build of their crates (docs/BENCHMARKS.md §10v: the projection along the
normals against coordinate partitioning).

Setup: each example's crate written by `lagc build examples/M.lag -o DIR/M --runtime
RDIR` and built with `CARGO_TARGET_DIR=DIR/base` (the runtime to compare against) and
`DIR/new` (another runtime: point the crate's `lagc-runtime` path at it, target
`DIR/new`). The reference is the base build's direct run at rtol 1e-13 atol 1e-15, but
for the helix: its closed form (z = z0 − a t²/2, x = R cos(z/p), y = R sin(z/p) and
their derivatives), independent of lagc. The error is max |a − b| / max(|b|, 1) over
every column and 201 samples; the estimate is the summary's global_error_estimate.

    VARIANT=base|new DIR=/tmp/part python3 scripts/holonomic_projection_errors.py OUT.json [M,M,...]

The environment is passed on to the runs (the scratch of §10v read LAGC_PART and
LAGC_PARTLEVEL from it). Prints one line a run and writes OUT.json.
"""
import json, math, os, subprocess, sys

DIR = os.environ.get('DIR', '/tmp/part')
VARIANT = os.environ.get('VARIANT', 'new')
TAG = os.environ.get('TAG', VARIANT)
MODELS = ('bead_on_helix atwood_machine bead_in_spinning_tube bead_on_cycloid '
          'cartesian_pendulum four_bar_closure parallelogram_linkage particle_on_circle').split()
RTOLS = ['1e-6', '1e-7', '1e-8', '1e-9', '1e-10', '1e-11', '1e-12']


def binary(variant, model):
    return f'{DIR}/{variant}/release/lag-{model.replace("_", "-")}'


def load(path):
    lines = open(path).read().split('\n')
    return [list(map(float, x.split(','))) for x in lines[1:] if x]


def run(variant, model, method, rtol, atol=None):
    os.makedirs(f'{DIR}/out', exist_ok=True)
    out = f'{DIR}/out/{TAG}_{variant}_{model}_{method}_{rtol}.csv'
    atol = atol or '%g' % (float(rtol) / 100)
    p = subprocess.run([binary(variant, model), '--method', method, '--rtol', rtol,
                        '--atol', atol, '--samples', '201', '-o', out, '--summary', 'json'],
                       capture_output=True, text=True)
    js = [x for x in p.stderr.splitlines() if x.startswith('{')]
    if p.returncode != 0 or not js:
        return None, None
    return json.loads(js[-1]), load(out)


def diff(a, b):
    return max((abs(x - y) / max(abs(y), 1) for ra, rb in zip(a, b)
                for x, y in zip(ra[1:], rb[1:])), default=0.0)


def helix(rows):
    g, R, p, z0 = 9.81, 0.5, 0.2, 3.0
    a = g / (1 + R * R / p / p)
    out = []
    for r in rows:
        t = r[0]
        z = z0 - a * t * t / 2
        out.append([t, R * math.cos(z / p), R * math.sin(z / p), z,
                    R * math.sin(z / p) * a * t / p, -R * math.cos(z / p) * a * t / p, -a * t])
    return out


def main():
    models = sys.argv[2].split(',') if len(sys.argv) > 2 else MODELS
    results = {}
    for model in models:
        _, reference = run('base', model, 'direct', '1e-13', '1e-15')
        if model == 'bead_on_helix':
            reference = helix(reference)
        for method in ['direct', 'field']:
            for rtol in RTOLS:
                key = f'{model} {method} {rtol}'
                summary, rows = run(VARIANT, model, method, rtol)
                if summary is None:
                    results[key] = {'fail': True}
                    print(key, 'FAIL', flush=True)
                    continue
                r = {'err': diff(rows, reference), 'est': summary.get('global_error_estimate'),
                     'exact': summary.get('exact_error'), 'rhs': summary.get('rhs_evaluations')}
                results[key] = r
                print(f"{model:22s} {method:6s} {rtol:6s} err {r['err'] / float(rtol):8.2f} rtol"
                      f"  est {(r['est'] or 0) / float(rtol):8.2f}  rhs {r['rhs']}", flush=True)
    json.dump(results, open(sys.argv[1], 'w'), indent=1)


if __name__ == '__main__':
    main()
