#!/usr/bin/env python3
"""A tail-swing sweep from Python: the paper's Fig. 7 case (1-link tail, dT = 0.25 s) with the swing
angle dtheta from -10 to -170 deg, run on a thread pool (tailsim releases the GIL while it simulates).

Writes OUT/sweep.csv (dtheta_deg, phi_net_deg, t_stop_s, model) and, if matplotlib is installed,
OUT/sweep.png. Optionally measures the speed-up of the pool over one thread.

usage: PYTHONPATH=build/python python3 examples/sweep.py [--out DIR] [--threads N] [--cases N]
           [--models analytic mujoco] [--speedup]
"""
import argparse
import concurrent.futures
import csv
import os
import time

import tailsim

BASE = dict(robot="paper", tail={"links": 1}, quadruped={"d_Q2B_m": 0.125})


def phi_net(dtheta_deg, model):
    """One case: the net body yaw [deg] and when the body stopped [s]."""
    r = tailsim.simulate(**BASE, model=model,
                         trajectory={"theta0_deg": 0, "dtheta_deg": dtheta_deg, "dT_s": 0.25, "w_ss": 0.25})
    return r.summary["phi_net_deg"], r.summary["t_stop_s"]


def sweep(dthetas, model, threads):
    with concurrent.futures.ThreadPoolExecutor(threads) as pool:
        return list(pool.map(lambda d: phi_net(d, model), dthetas))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="results/sweep_py")
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--cases", type=int, default=17, help="dtheta values between -10 and -170 deg")
    ap.add_argument("--models", nargs="+", default=["analytic"], choices=tailsim.models())
    ap.add_argument("--speedup", action="store_true",
                    help="time the sweep of the first model on 1 and on --threads threads (the results must not change)")
    a = ap.parse_args()
    n = max(a.cases, 2)
    dthetas = [-10 - 160 * k / (n - 1) for k in range(n)]
    os.makedirs(a.out, exist_ok=True)

    results = {m: sweep(dthetas, m, a.threads) for m in a.models}
    path = os.path.join(a.out, "sweep.csv")
    with open(path + ".tmp", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["model", "dtheta_deg", "phi_net_deg", "t_stop_s"])
        for m in a.models:
            for d, (phi, t_stop) in zip(dthetas, results[m]):
                w.writerow([m, repr(d), repr(phi), repr(t_stop)])
    os.replace(path + ".tmp", path)  # whole or not at all
    print(f"{path}: {n} cases x {len(a.models)} model(s)")

    if a.speedup:
        m = a.models[0]
        times = {}
        for t in (1, a.threads):
            start = time.perf_counter()
            again = sweep(dthetas, m, t)
            times[t] = time.perf_counter() - start
            if again != results[m]:
                raise SystemExit(f"the {t}-thread sweep changed a result")
        print(f"speed-up: {n} {m} cases, 1 thread {times[1]:.3f} s, {a.threads} threads {times[a.threads]:.3f} s:"
              f" x{times[1] / times[a.threads]:.2f}")

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not installed: no plot (the CSV has the numbers)")
        return
    colors = {"analytic": "#0072B2", "mujoco": "#D55E00", "perfoot": "#009E73"}  # Okabe-Ito, as tailsim's plots
    fig, ax = plt.subplots(figsize=(6, 4))
    for m in a.models:
        ax.plot([-d for d in dthetas], [p for p, _ in results[m]], "o-", color=colors.get(m), label=m)
    ax.set_xlabel("tail swing |Δθ| [deg]")
    ax.set_ylabel("net body rotation φ_net [deg]")
    ax.set_title("Net turn over tail swing angle (1-link tail, ΔT = 0.25 s)")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    png = os.path.join(a.out, "sweep.png")
    fig.savefig(png + ".tmp.png", dpi=120)
    os.replace(png + ".tmp.png", png)
    print(png)


if __name__ == "__main__":
    main()
