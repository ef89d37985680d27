#!/usr/bin/env python3
"""Whole-process CPU time of two commands, alternated, and their ratio pair by pair.

usage: cpu_ratio.py [-n RUNS] [--per A_COUNT B_COUNT] [--key NAME] -- 'COMMAND A' 'COMMAND B'

Runs B once and A once untimed, then A, B, A, B, ... RUNS times each; each run's CPU time is
user + system of the finished child as the operating system accounts it (os.wait4's rusage,
what /usr/bin/time reports), so a shared machine's load moves it far less than wall time.
Prints one JSON line: each command's CPU seconds per run, their medians, the ratio A/B of
every pair and its median, and the load average (/proc/loadavg) before and after. With
--per, the ratio is also given per unit of work: (A/A_COUNT) / (B/B_COUNT) pair by pair
(e.g. collisions per process). With --key, each command's last output line is read as JSON
and the ratio of its NAME members is also given pair by pair (e.g. `cpu_per_collision_s`,
which the peers in this folder and `impact_bench --collisions` print: CPU time measured inside
the process, its start-up excluded). The commands are split as a shell splits words, without
a shell (shlex).
"""
import json
import os
import shlex
import statistics
import subprocess
import sys


def cpu_of(argv, key=None):
    """(CPU seconds of the finished child, its `key` member or None)."""
    p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    out = p.stdout.read()
    _, status, ru = os.wait4(p.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"{argv[0]} failed: status {status}")
    value = json.loads(out.strip().splitlines()[-1])[key] if key else None
    return ru.ru_utime + ru.ru_stime, value


def loadavg():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def main():
    args = sys.argv[1:]
    runs, per, key = 5, None, None
    while args and args[0] != "--":
        if args[0] == "-n":
            runs, args = int(args[1]), args[2:]
        elif args[0] == "--key":
            key, args = args[1], args[2:]
        elif args[0] == "--per":
            per, args = (float(args[1]), float(args[2])), args[3:]
        else:
            sys.exit(__doc__)
    if len(args) != 3:
        sys.exit(__doc__)
    a, b = shlex.split(args[1]), shlex.split(args[2])
    load0 = loadavg()
    cpu_of(b), cpu_of(a)  # untimed
    ta, tb, ka, kb = [], [], [], []
    for _ in range(runs):
        for argv, t, k in ((a, ta, ka), (b, tb, kb)):
            cpu, value = cpu_of(argv, key)
            t.append(cpu)
            k.append(value)
    ratios = [x / y for x, y in zip(ta, tb)]
    out = {"a": args[1], "b": args[2], "cpu_a_s": ta, "cpu_b_s": tb,
           "median_a_s": statistics.median(ta), "median_b_s": statistics.median(tb),
           "ratio_pairs": ratios, "ratio_median": statistics.median(ratios),
           "load_before": load0, "load_after": loadavg()}
    if per:
        out["ratio_per_unit_median"] = statistics.median(r * per[1] / per[0] for r in ratios)
    if key:
        kr = [x / y for x, y in zip(ka, kb)]
        out.update({f"{key}_a": ka, f"{key}_b": kb, f"{key}_ratio_pairs": kr,
                    f"{key}_ratio_median": statistics.median(kr)})
    print(json.dumps(out))


if __name__ == "__main__":
    main()
