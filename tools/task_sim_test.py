#!/usr/bin/env python3
"""Checks tools/task_sim.py on traces whose outcome is known by hand; exits 1 on a failure."""
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
# The binary that reads a params file as the firmware does: argv[1], else the build's.
RGBDTAM = ['--rgbdtam', sys.argv[1]] if len(sys.argv) > 1 else []
HEADER = 'stamp_ns,sensor_ns,tracker_ns,keyframe,build_ns,mapper_items,mapper_ns,loop_items,loop_ns\n'
MS = 1_000_000


def simulate(rows, board_lines, scale=''):
    with tempfile.TemporaryDirectory() as d:
        os.makedirs(os.path.join(d, 'board'))
        with open(os.path.join(d, 'board', 'board.conf'), 'w') as f:
            f.write('board.name = test\nsensor.kind = freenect\nsensor.fps = 30\n' + board_lines)
        with open(os.path.join(d, 'params.conf'), 'w') as f:
            f.write('camera.width = 640\ncamera.height = 480\ncamera.fx = 525\ncamera.fy = 525\n'
                    'camera.cx = 319.5\ncamera.cy = 239.5\ndepth.factor = 5000\n'
                    'map.queue_frames = 4\nloop.queue_keyframes = 1\n')
        with open(os.path.join(d, 'trace.csv'), 'w') as f:
            f.write(HEADER)
            for r in rows:
                f.write(','.join(str(v) for v in r) + '\n')
        out = subprocess.run([sys.executable, os.path.join(HERE, 'task_sim.py'),
                              os.path.join(d, 'trace.csv'), '--board', os.path.join(d, 'board'),
                              '--config', os.path.join(d, 'params.conf'), '--scale', scale or
                              'tracker=1'] + RGBDTAM, capture_output=True, text=True,
                             check=True).stdout
    numbers = {}
    for key, pattern in {'misses': r'deadline misses (\d+)', 'dropped': r'dropped frames (\d+)',
                         'awaiting': r'meanwhile (\d+)', 'deferred': r'in flight (\d+)',
                         'mapper_drops': r'queue \(\d+\) drops (\d+) \(',
                         'mapper_skipped': r'(\d+) frames skipped',
                         'latency_median': r'median ([\d.]+)'}.items():
        numbers[key] = float(re.search(pattern, out).group(1))
    return numbers, out


def row(tracker_ms, keyframe=0, build_ms=0, mapper_ms=0):
    return (0, 0, tracker_ms * MS, keyframe, build_ms * MS, 1 if mapper_ms else 0,
            mapper_ms * MS, 0, 0)


failures = []


def check(name, condition, out):
    if not condition:
        failures.append(f'{name}:\n{out}')


two_cores = 'board.cpu_count = 2\nthreads.tracker_cpu = 0\nthreads.builder_cpu = 1\n' \
            'threads.mapper_cpu = 1\nthreads.loop_cpu = 1\n'
# 10 ms of tracking per 33 ms frame: every frame in time, latency the tracking time.
n, out = simulate([row(10)] * 30, two_cores)
check('a light tracker', n['misses'] == 0 and n['dropped'] == 0 and
      abs(n['latency_median'] - 10) < 0.5, out)
# 50 ms per frame: every frame late, and the mailbox keeps only the newest.
n, out = simulate([row(50)] * 30, two_cores)
check('a tracker slower than the frames', n['misses'] >= 15 and n['dropped'] >= 5, out)
# The same trace at half the time on a faster board.
n, out = simulate([row(50)] * 30, two_cores, 'tracker=0.5')
check('a scaled tracker', n['misses'] == 0 and abs(n['latency_median'] - 25) < 0.5, out)
# A keyframe that takes 100 ms to build: three frames tracked against the last one, and a
# keyframe asked for meanwhile waits.
n, out = simulate([row(5, 1, 100)] + [row(5)] * 2 + [row(5, 1, 100)] + [row(5)] * 10, two_cores)
check('a slow builder', n['awaiting'] >= 2 and n['deferred'] == 1, out)
# A mapper at 200 ms per frame behind a four-frame queue skips the frames waiting behind the one
# in hand, then the queue drops the rest while it works.
n, out = simulate([row(5, 0, 0, 200)] * 20, two_cores)
check('a slow mapper', n['mapper_skipped'] >= 3 and n['mapper_drops'] >= 5, out)
# On one core, a tracker at SCHED_FIFO is not slowed by the mapper beside it.
one_core = 'board.cpu_count = 1\nthreads.tracker_cpu = 0\nthreads.tracker_priority = 50\n' \
           'threads.builder_cpu = 0\nthreads.mapper_cpu = 0\nthreads.loop_cpu = 0\n'
n, out = simulate([row(10, 0, 0, 20)] * 20, one_core)
check('priority on a shared core', abs(n['latency_median'] - 10) < 0.5, out)

for f in failures:
    print('FAILED', f)
print(f'task_sim: {6 - len(failures)} of 6 checks passed')
sys.exit(1 if failures else 0)
