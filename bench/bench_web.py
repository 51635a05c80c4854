"""The live view's cost: latency from sample to page, bytes per page, the server's CPU and memory.

Starts ``imucalib serve`` on 127.0.0.1 (its own process, a fresh records database, an operator
with a password) and a P2 twin run at 1 kHz with its chamber, paced to wall time (``pace``,
docs/web-runs.md): two units on the cube, a short soak at each of two temperatures, statics and
rates; the bench answers the run's remount prompts through the supervisor. It then opens
WebSocket pages on ``/ws/runs/{id}`` (the ``websockets`` client, the session cookie of one
login): first 1 page, then ``--pages`` (10) pages at once, each phase ``--seconds`` long, and
measures per phase:

- sample → page latency: the worker stamps each state it writes (``signals.wall_unix``, the
  wall time right after the runner's tick delivered the samples); a page's receive time minus
  it, p50 and p95 over every live-sample event of every page (but its first, the state as it
  was when the page subscribed);
- events and bytes a second per page;
- the server's CPU (user + system time of its process over the phase's wall time) and its
  resident memory (``VmRSS``), sampled every second; the run's worker process besides (its
  first, last and largest, and its trend after the first minute and over the second half of
  both phases: the worker builds the twin and fills its caches for some minutes first).

Run:  .venv/bin/python bench/bench_web.py [--seconds 60] [--pages 10] [--pace 1] [--points 2]
      (``--seconds 900 --points 4``: the "memory flat over a 30-minute run" check.)
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import platform
import re
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import websockets

from imucalib.web.supervisor import RunSupervisor

PASSWORD = "bench password 1"
OPERATOR = "Bea Bench"


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def _users(url: str) -> None:
    from imucalib.records import access, open_records

    access.ARGON2_PARAMS = {"time_cost": 1, "memory_cost": 1024, "parallelism": 1}
    with open_records(url) as records:
        records.add_user("Ada Admin", "AA", "admin")
        records.set_password("Ada Admin", PASSWORD, by="Ada Admin")
        records.add_user(OPERATOR, "BB", "operator", by="Ada Admin")
        records.set_password(OPERATOR, PASSWORD, by="Ada Admin")


def _plan(folder: Path, points: int) -> Path:
    from imucalib.plan import write_plan
    from imucalib.procedures.p2.plan import generate_p2_plan

    temperatures = tuple(25.0 + 5.0 * k for k in range(points))
    plan = generate_p2_plan(n_imus=2, temperatures_degc=temperatures, held_out_degc=(),
                            rate_dps=60.0, revolutions=1, static_s=10.0, settle_s=5.0,
                            ramp_degc_per_min=10.0, stable_for_s=30.0, resoak_s=0.0,
                            sample_rate_hz=1000.0, name="bench-web-p2")
    return write_plan(plan, folder / "bench-web-p2.toml")


def _proc(pid: int) -> tuple[float, float]:
    """Return (RSS [MiB], user + system CPU time [s]) of a process."""
    status = Path(f"/proc/{pid}/status").read_text()
    rss_kib = float(re.search(r"VmRSS:\s+(\d+)", status).group(1))  # type: ignore[union-attr]
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    ticks = os.sysconf("SC_CLK_TCK")
    return rss_kib / 1024.0, (int(fields[11]) + int(fields[12])) / ticks


def _login(base: str) -> str:
    with httpx.Client(base_url=base) as client:
        page = client.get("/login").text
        token = re.search(r'name="form_token" value="([^"]+)"', page)
        assert token, page[:300]
        answer = client.post("/login", data={"name": OPERATOR, "password": PASSWORD,
                                              "form_token": token.group(1)})
        assert answer.status_code in (200, 303), answer.text[:300]
        return "; ".join(f"{k}={v}" for k, v in client.cookies.items())


async def _page(url: str, cookie: str, origin: str, until: float,
                out: dict[str, Any]) -> None:
    async with websockets.connect(url, additional_headers={"Cookie": cookie, "Origin": origin},
                                  max_size=None) as ws:
        while (left := until - time.time()) > 0:
            try:
                text = await asyncio.wait_for(ws.recv(), timeout=left)
            except TimeoutError:
                break
            now = time.time()
            data = text.encode() if isinstance(text, str) else text
            out["bytes"] += len(data)
            out["events"] += 1
            event = json.loads(data)
            if event.get("type") != "signals":
                continue
            out["signals"] += 1
            stamp = (event.get("signals") or {}).get("wall_unix")
            if out["signals"] > 1 and isinstance(stamp, float):  # the first: the state
                out["latency"].append(now - stamp)                # as it was at subscribe


async def _phase(n: int, url: str, cookie: str, origin: str, seconds: float
                 ) -> list[dict[str, Any]]:
    until = time.time() + seconds
    pages = [{"bytes": 0, "events": 0, "signals": 0, "latency": []} for _ in range(n)]
    await asyncio.gather(*(_page(url, cookie, origin, until, p) for p in pages))
    return pages


def _answer_prompts(sup: RunSupervisor, run_id: str, stop: threading.Event) -> None:
    while not stop.wait(0.2):
        try:
            v = sup.view(run_id)
            if v.prompt is not None:
                sup.answer(run_id, v.prompt.prompt_id, v.prompt.step_index, True, OPERATOR)
        except Exception as exc:  # a prompt that closed meanwhile: look again
            print(f"  (prompt: {type(exc).__name__}: {exc})", file=sys.stderr)


def _slope(phase: list[tuple[float, float]], skip_s: float = 60.0,
           what: str = "after its first minute") -> str:
    """Return the RSS trend after `skip_s` of `phase` (least squares), as text."""
    late = [(t, r) for t, r in phase if t - phase[0][0] >= skip_s]
    if len(late) < 60:
        return ""
    t, r = np.array(late).T
    per_min = 60.0 * float(np.polyfit(t, r, 1)[0])
    return f"; trend {what} {per_min:+.3f} MiB/min"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="length of each phase [s]")
    parser.add_argument("--pages", type=int, default=10)
    parser.add_argument("--pace", type=float, default=1.0, help="wall s per station s")
    parser.add_argument("--points", type=int, default=2,
                        help="temperature points of the plan (25, 30, … °C)")
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench-web-"))
    url = f"sqlite:///{tmp / 'records.db'}"
    _users(url)
    plan = _plan(tmp, args.points)
    port = _free_port()
    base, runs = f"http://127.0.0.1:{port}", tmp / "runs"
    server = subprocess.Popen([sys.executable, "-m", "imucalib", "serve", "--port", str(port),
                               "--records", url, "--runs-dir", str(runs), "--station",
                               "bench-web"], stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, env={**os.environ,
                                                           "XDG_CONFIG_HOME": str(tmp / "c")})
    sup = RunSupervisor(runs, record=False)
    stop = threading.Event()
    samples: list[tuple[float, float, float | None]] = []
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=0.5):
                    break
            except OSError:
                if time.monotonic() > deadline or server.poll() is not None:
                    raise SystemExit("the server did not start") from None
                time.sleep(0.1)
        cookie = _login(base)
        run_id = sup.start(plan, station="sim", serials=[], operator=OPERATOR, pace=args.pace)
        threading.Thread(target=_answer_prompts, args=(sup, run_id, stop), daemon=True).start()
        worker_pid = int((runs / run_id / "worker.pid").read_text())

        def sample_memory() -> None:
            t0 = time.time()
            while not stop.wait(1.0):
                try:
                    rss, _ = _proc(server.pid)
                    wrss = _proc(worker_pid)[0] if Path(f"/proc/{worker_pid}").exists() else None
                except OSError:
                    continue
                samples.append((time.time() - t0, rss, wrss))

        threading.Thread(target=sample_memory, daemon=True).start()
        ws_url = f"ws://127.0.0.1:{port}/ws/runs/{run_id}"
        rows = []
        phases = []
        for n in (1, args.pages):
            _, cpu0 = _proc(server.pid)
            w0 = time.time()
            first = len(samples)
            pages = asyncio.run(_phase(n, ws_url, cookie, base, args.seconds))
            wall = time.time() - w0
            _, cpu1 = _proc(server.pid)
            phases.append((n, [(s[0], s[1]) for s in samples[first:]]))
            lat = np.array([x for p in pages for x in p["latency"]])
            p50, p95 = np.percentile(lat, [50, 95]) if lat.size else (np.nan, np.nan)
            rows.append((n, p50, p95,
                         sum(p["events"] for p in pages) / n / wall,
                         sum(p["bytes"] for p in pages) / n / wall,
                         100.0 * (cpu1 - cpu0) / wall, lat.size))
        view = sup.view(run_id)
    finally:
        stop.set()
        sup.close()
        server.terminate()
        server.wait(timeout=20)
        pid_file = runs.glob("*/worker.pid")
        for f in pid_file:
            try:
                os.kill(int(f.read_text()), 15)
            except (ProcessLookupError, ValueError):
                pass
    print(f"bench_web — {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs, Python {platform.python_version()}; twin P2, 2 units at "
          f"1 kHz, chamber, pace {args.pace:g}; {args.seconds:g} s per phase")
    print(f"run {run_id}: {view.status}, step {view.step_index + 1} of {view.n_steps}")
    print()
    print("| pages | latency p50 [ms] | p95 [ms] | events/s per page | bytes/s per page "
          "| server CPU [% of a core] | samples |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for n, p50, p95, eps, bps, cpu, count in rows:
        print(f"| {n} | {1e3 * p50:.0f} | {1e3 * p95:.0f} | {eps:.1f} | {bps:,.0f} | {cpu:.1f} "
              f"| {count} |")
    print()
    if samples:
        rss = [s[1] for s in samples]
        third = max(1, len(rss) // 3)
        worker = [s[2] for s in samples if s[2] is not None]
        for n, phase in phases:
            rss_phase = [r for _t, r in phase]
            k = max(1, min(30, len(rss_phase) // 4))
            if rss_phase:
                print(f"server RSS [MiB] with {n} page(s): first {k} s mean "
                      f"{statistics.mean(rss_phase[:k]):.1f}, last {k} s mean "
                      f"{statistics.mean(rss_phase[-k:]):.1f}{_slope(phase)}")
        print(f"server RSS [MiB]: first third mean {statistics.mean(rss[:third]):.1f}, last "
              f"third mean {statistics.mean(rss[-third:]):.1f}, max {max(rss):.1f} "
              f"({len(rss)} samples over {samples[-1][0]:.0f} s)")
        if worker:
            worker_rows = [(s[0], s[2]) for s in samples if s[2] is not None]
            half_s = (worker_rows[-1][0] - worker_rows[0][0]) / 2
            print(f"worker RSS [MiB]: first {worker[0]:.1f}, at half time "
                  f"{worker_rows[len(worker_rows) // 2][1]:.1f}, last {worker[-1]:.1f}, "
                  f"max {max(worker):.1f}{_slope(worker_rows)}"
                  f"{_slope(worker_rows, half_s, 'over the second half')}")


if __name__ == "__main__":
    main()
