"""Wall time of the README's test command on fresh clones, several times in a row.

Each round clones the repository's committed HEAD into a temporary folder, makes a virtual environment that sees
the installed packages (``--system-site-packages``: the dependencies are not downloaded again, the package itself
is installed fresh, its C core built by ``pip install``), and runs the README's second command (line 3 of
README.md) there, its two halves (split at ``&&``) one after the other with ``bash -c``, each timed; the
round's time is their sum.  The third-party
fixture FMUs that ``.ci/run`` fetches into ``.cache/thirdparty`` are copied into the clone when present, as CI
has them.  Prints one line per round with the load averages before and after; the installed package outside the
virtual environment is not touched.

Usage: ``python benchmarks/readme_test_timing.py [--rounds 5]``
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Round:
    """One fresh-clone run: seconds for the command's two halves; pytest's last line."""
    install_s: float
    tests_s: float
    summary: str
    load_before: tuple[float, float, float]
    load_after: tuple[float, float, float]

    @property
    def total_s(self) -> float:
        """The whole command (s)."""
        return self.install_s + self.tests_s


def readme_test_command(readme: Path) -> str:
    """The second line of README.md's leading code block (its line 3)."""
    lines = readme.read_text(encoding="utf-8").splitlines()
    if not lines or not lines[0].startswith("```"):
        raise SystemExit("README.md does not start with a code block")
    return lines[2].strip()


def _timed(cmd: str, cwd: Path, env: dict[str, str]) -> tuple[float, subprocess.CompletedProcess]:
    t0 = time.perf_counter()
    done = subprocess.run(["bash", "-c", cmd], cwd=cwd, env=env, capture_output=True, text=True)
    return time.perf_counter() - t0, done


def one_round(work: Path) -> Round:
    """Clone, make the environment, run the command's two halves (split at ``&&``) one after the other."""
    clone = work / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    cached = ROOT / ".cache" / "thirdparty"
    if cached.is_dir():
        (clone / ".cache").mkdir()
        shutil.copytree(cached, clone / ".cache" / "thirdparty",
                        ignore=shutil.ignore_patterns("kf-gins"))
    venv = work / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    env = dict(os.environ, PATH=f"{venv / 'bin'}{os.pathsep}{os.environ['PATH']}", VIRTUAL_ENV=str(venv))
    env.pop("PYTHONPATH", None)
    install, tests = (part.strip() for part in readme_test_command(clone / "README.md").split("&&", 1))
    load_before = os.getloadavg()
    install_s, done = _timed(install, clone, env)
    if done.returncode != 0:
        raise SystemExit(f"{install!r} failed:\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    tests_s, done = _timed(tests, clone, env)
    lines = [ln for ln in done.stdout.splitlines() if ln.strip()]
    summary = lines[-1] if lines else "(no output)"
    if done.returncode != 0:
        failed = "\n".join(ln for ln in lines if ln.startswith(("FAILED", "ERROR")))
        raise SystemExit(f"{tests!r} failed: {summary}\n{failed}")
    return Round(install_s, tests_s, summary, load_before, os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                          check=True).stdout.strip()
    print(f"README test command at {head}: {readme_test_command(ROOT / 'README.md')}  ({os.cpu_count()} CPUs)")
    for k in range(args.rounds):
        with tempfile.TemporaryDirectory(prefix="sarins-fresh-") as tmp:
            r = one_round(Path(tmp))
        print(f"round {k + 1}: {r.total_s:6.1f} s (pip {r.install_s:5.1f} s, pytest {r.tests_s:6.1f} s)  "
              f"load {r.load_before[0]:.2f} -> {r.load_after[0]:.2f}  {r.summary}", flush=True)


if __name__ == "__main__":
    main()
