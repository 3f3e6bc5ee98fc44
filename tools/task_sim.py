#!/usr/bin/env python3
"""The whole firmware at a board's shape, by simulation.

Replays a per-frame trace of a synchronous replay (`rgbdtam replay ... --trace trace.csv`: each
module's time per frame on this machine) through a board's task table: frames arrive at the
sensor's rate into a one-frame mailbox (the newest kept, as the firmware's sensor does), the
tracker tracks each and orders the keyframes the trace built, the keyframe builder, mapper and
loop module take their work from queues of the configured sizes, and each core runs its ready
tasks by priority (SCHED_FIFO before the normal scheduler, which shares a core equally). Each
module's time is scaled by its own ratio (the board's time over this machine's: from the cycle
model of tools/aarch64_cost.sh). Prints deadline misses, dropped frames, queue drops, how late
keyframes came, frame-to-ODOMETRY latency and each core's load.

  tools/task_sim.py <trace.csv> --board <board-folder> [--config <params file>]
                    [--scale tracker=R,builder=R,mapper=R,loop=R,sensor=R] [--fps N] [--tick-us N]
                    [--rgbdtam build/bin/rgbdtam]

--config defaults to the board's sensor.config; its map.queue_frames and loop.queue_keyframes
(as `rgbdtam params` reads them, defaults included) size the queues. The sensor's work
(decoding the recording) counts only on a replay board.
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys


def read_keys(path):
    keys = {}
    with open(path) as f:
        for line in f:
            line = line.split('#', 1)[0].strip()
            if '=' in line:
                k, v = line.split('=', 1)
                keys[k.strip()] = v.strip()
    return keys


def percentile(values, p):
    if not values:
        return 0.0
    s = sorted(values)
    return s[min(len(s) - 1, int(p * len(s)))]


class Task:
    def __init__(self, name, cpu, priority):
        self.name, self.cpu, self.priority = name, cpu, priority
        self.jobs = []  # [remaining_s, payload], oldest first
        self.busy_s = 0.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    ap.add_argument('trace')
    ap.add_argument('--board', required=True)
    ap.add_argument('--config')
    ap.add_argument('--scale', default='')
    ap.add_argument('--fps', type=float)
    ap.add_argument('--tick-us', type=float, default=100.0)
    ap.add_argument('--rgbdtam', default=os.path.join(os.path.dirname(__file__), '..', 'build',
                                                      'bin', 'rgbdtam'))
    a = ap.parse_args()

    board = read_keys(os.path.join(a.board, 'board.conf'))
    config = a.config or os.path.join(a.board, board.get('sensor.config', ''))
    if not os.path.isfile(config):
        sys.exit(f'task_sim: no params file {config!r}: give --config')
    out = subprocess.run([a.rgbdtam, 'params', '--config', config], capture_output=True,
                         text=True)
    if out.returncode != 0:
        sys.exit(f'task_sim: {a.rgbdtam} params --config {config}: {out.stderr.strip()}')
    params = {}
    for line in out.stdout.splitlines():
        key, _, value = line.split('#', 1)[0].partition('=')
        params[key.strip()] = value.strip()
    cpus = int(board.get('board.cpu_count', '1'))
    fps = a.fps or float(board.get('sensor.fps', '30'))
    scale = {'tracker': 1.0, 'builder': 1.0, 'mapper': 1.0, 'loop': 1.0, 'sensor': 1.0}
    for item in filter(None, a.scale.split(',')):
        name, value = item.split('=')
        if name not in scale:
            sys.exit(f'task_sim: --scale names {name!r}; known: {", ".join(scale)}')
        scale[name] = float(value)
    if board.get('sensor.kind') != 'replay':
        scale['sensor'] = 0.0  # a real sensor's frames need no decoding
    map_queue = int(params['map.queue_frames'])
    loop_queue = int(params['loop.queue_keyframes'])

    with open(a.trace) as f:
        rows = [{k: int(v) for k, v in r.items()} for r in csv.DictReader(f)]
    if not rows:
        sys.exit('task_sim: the trace has no frames')

    def task(name):
        cpu = int(board.get(f'threads.{name}_cpu', '-1'))
        if cpu >= cpus:
            sys.exit(f'task_sim: threads.{name}_cpu {cpu} but the board has {cpus} CPUs')
        return Task(name, cpu, int(board.get(f'threads.{name}_priority', '0')))

    tasks = {n: task(n) for n in ('sensor', 'tracker', 'builder', 'mapper', 'loop')}
    # A task free to run anywhere takes the CPU the others leave (the last one's, else 0).
    for t in tasks.values():
        if t.cpu < 0:
            pinned = {u.cpu for u in tasks.values() if u.cpu >= 0}
            t.cpu = next((c for c in range(cpus - 1, -1, -1) if c not in pinned), 0)

    tick = a.tick_us * 1e-6
    period = 1.0 / fps
    mailbox = None  # the frame the tracker takes next (newest kept)
    building_until_frame = None  # the frame index of the keyframe in flight
    stats = dict(misses=0, dropped=0, mapper_dropped=0, mapper_dropped_keyframes=0,
                 mapper_skipped=0, loop_dropped=0, keyframes=0, keyframes_deferred=0, frames_awaiting=0)
    latency_ms = []
    delivered = {}
    n = len(rows)
    t = 0.0
    next_frame = 0
    end = n * period + 60.0
    while t < end:
        # Arrivals: the sensor's work first, then the mailbox.
        while next_frame < n and next_frame * period <= t + 1e-12:
            r = rows[next_frame]
            tasks['sensor'].jobs.append([r['sensor_ns'] * 1e-9 * scale['sensor'], next_frame])
            next_frame += 1
        for job in [j for j in tasks['sensor'].jobs if j[0] <= 0]:
            tasks['sensor'].jobs.remove(job)
            if mailbox is not None:
                stats['dropped'] += 1
            mailbox = job[1]
            delivered[job[1]] = t  # the firmware's arrival: the frame handed to the tracker
        tr = tasks['tracker']
        if not tr.jobs and mailbox is not None:
            tr.jobs.append([rows[mailbox]['tracker_ns'] * 1e-9 * scale['tracker'], mailbox])
            mailbox = None
        # Each core: the highest priority's ready tasks share the tick.
        for cpu in range(cpus):
            ready = [u for u in tasks.values() if u.cpu == cpu and u.jobs]
            if not ready:
                continue
            top = max(u.priority for u in ready)
            running = [u for u in ready if u.priority == top]
            for u in running:
                u.jobs[0][0] -= tick / len(running)
                u.busy_s += tick / len(running)
        t += tick
        # Completions.
        if tr.jobs and tr.jobs[0][0] <= 0:
            i = tr.jobs.pop(0)[1]
            arrival = delivered[i]
            latency_ms.append((t - arrival) * 1e3)
            if t > arrival + period:
                stats['misses'] += 1
            r = rows[i]
            if building_until_frame is not None:
                stats['frames_awaiting'] += 1
            if r['keyframe']:
                if building_until_frame is None:
                    tasks['builder'].jobs.append([r['build_ns'] * 1e-9 * scale['builder'], i])
                    building_until_frame = i
                    stats['keyframes'] += 1
                else:
                    stats['keyframes_deferred'] += 1
            if r['mapper_items'] > 0:
                if len(tasks['mapper'].jobs) >= map_queue:
                    stats['mapper_dropped'] += 1
                    stats['mapper_dropped_keyframes'] += r['keyframe']
                else:
                    tasks['mapper'].jobs.append([r['mapper_ns'] * 1e-9 * scale['mapper'], i])
            if r['loop_items'] > 0:
                if len(tasks['loop'].jobs) >= loop_queue:
                    stats['loop_dropped'] += 1
                else:
                    tasks['loop'].jobs.append([r['loop_ns'] * 1e-9 * scale['loop'], i])
        b = tasks['builder']
        if b.jobs and b.jobs[0][0] <= 0:
            b.jobs.pop(0)
            building_until_frame = None
        q = tasks['loop']
        if q.jobs and q.jobs[0][0] <= 0:
            q.jobs.pop(0)
        m = tasks['mapper'].jobs
        if m and m[0][0] <= 0:
            m.pop(0)
            # The next frame in hand, when late (half the queue or more waiting behind it), is
            # not observed unless it is a keyframe (MappingModule::late).
            while len(m) > 1 and len(m) - 1 >= map_queue // 2 and not rows[m[0][1]]['keyframe']:
                m.pop(0)
                stats['mapper_skipped'] += 1
        if next_frame >= n and mailbox is None and not any(u.jobs for u in tasks.values()):
            break

    frames = len(rows)
    print(f'board {board.get("board.name", a.board)}: {frames} frames at {fps:g} Hz, '
          f'scales {", ".join(f"{k} {v:g}" for k, v in scale.items())}')
    print(f'deadline misses {stats["misses"]}, dropped frames {stats["dropped"]} (newest kept)')
    print(f'keyframes built {stats["keyframes"]}, asked while one was in flight '
          f'{stats["keyframes_deferred"]}, frames tracked against the last one meanwhile '
          f'{stats["frames_awaiting"]}')
    print(f'mapper: {stats["mapper_skipped"]} frames skipped to catch up, queue '
          f'({map_queue}) drops {stats["mapper_dropped"]} ({stats["mapper_dropped_keyframes"]} '
          f'keyframes); loop queue ({loop_queue}) drops {stats["loop_dropped"]}')
    print(f'latency, frame arrival to ODOMETRY, ms: median {statistics.median(latency_ms):.2f}, '
          f'p95 {percentile(latency_ms, 0.95):.2f}, max {max(latency_ms):.2f}')
    span = max(t, frames * period)
    load = ', '.join(
        f'cpu {c} {sum(u.busy_s for u in tasks.values() if u.cpu == c) / span * 100:.0f} % '
        f'({"+".join(u.name for u in tasks.values() if u.cpu == c) or "idle"})'
        for c in range(cpus))
    print(f'load: {load}')


if __name__ == '__main__':
    main()
