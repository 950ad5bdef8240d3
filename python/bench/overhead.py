"""What a `plan` call costs through Python beyond the planner's own budget (issue 45: at most
5 % of a 1 ms call).

    python python/bench/overhead.py [--calls 2000] [--repeats 5]

Three loops of `plan` calls on the built-in office_200 scenario, the goal set and the agent
standing at the start (so every call plans for its whole budget):

- `wall 1 ms`: the wall clock, t_exp 1 ms. Per call, the Python-measured time less 1 ms is
  the boundary's cost plus the planner's overrun of its deadline.
- `wall 1 us`: t_exp 1 us: the call returns after its first deadline check, so the time is
  the boundary's cost plus the planner's fixed work per call (an upper bound of the boundary).
- `virtual 1 ms`: the virtual clock (83,333 work units a call), for reference.

Prints the median per call of each loop (medians of `--repeats` runs) and the boundary's
share of a 1 ms call, bounded by the `wall 1 us` figure.
"""

import argparse
import statistics
import time

import bi_am_rrt as b


def loop(clock, t_exp_ms, calls):
    s = b.Scenario.builtin("office_200")
    p = b.Planner(s, clock=clock, t_exp_ms=t_exp_ms)
    p.set_goal(s.goals[0])
    agent = s.start
    for _ in range(50):  # warm up: caches, the tree's first nodes
        p.plan(agent)
    times = []
    for _ in range(calls):
        t0 = time.perf_counter_ns()
        p.plan(agent)
        times.append(time.perf_counter_ns() - t0)
    return statistics.median(times) / 1e3  # microseconds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    cases = [("wall 1 ms", "wall", 1.0), ("wall 1 us", "wall", 0.001), ("virtual 1 ms", "virtual", 1.0)]
    med = {}
    for name, clock, ms in cases:
        runs = [loop(clock, ms, a.calls) for _ in range(a.repeats)]
        med[name] = statistics.median(runs)
        print(f"{name:>13}: median {med[name]:8.1f} us a call (runs: {', '.join(f'{r:.1f}' for r in runs)})")
    print(f"beyond a 1 ms budget: {med['wall 1 ms'] - 1000:.1f} us a call "
          f"({(med['wall 1 ms'] - 1000) / 10:.2f} % of 1 ms; boundary and overrun)")
    print(f"a 1 us call whole: {med['wall 1 us']:.1f} us ({med['wall 1 us'] / 10:.2f} % of 1 ms; "
          f"an upper bound of the boundary's cost)")


if __name__ == "__main__":
    main()
