"""Where the time goes: a profile by stage of a call, for the benchmarks whose targets are not met
(issue 36). Methods of the core are wrapped with wall-clock accumulators for the duration of a
``with StageProfile() as profile:`` block (and restored after); ``profile.report(total)`` gives
each stage's seconds, calls and share of ``total``, the rest as "other (Python between stages)".

Each stage's time is its own, without the stages it calls: NLP builds, static solves (without
their Newton, assembly ...), CasADi's residual and Jacobian evaluations, SuperLU's factorisations
and triangular solves, Newton's loop (its Python between those), the Solution's assembly
(outputs, balances) and a dynamic run's energy account.
"""
import time
from collections import defaultdict


def _targets():
    """``(stage, class, method name)`` of every stage timed."""
    from tca_casadi.discretisation.structure import StructuredJacobian
    from tca_casadi.solvers import compiled, native
    from tca_casadi.solvers.collocation import CollocationSolver
    from tca_casadi.studies.sweep.run import Sweep
    from tca_casadi.solvers.native import NativeChord
    from tca_casadi.solvers.newton import OrderedLU, SquareSystem
    from tca_casadi.simulation import Simulation
    from tca_casadi.time_simulation.motion import EnergyAccount
    return [("NLP builds", CollocationSolver, "__init__"),
            ("C compiles (solver.jit; kept on disk)", compiled, "compiled_library"),
            ("C compiles (solver.jit; kept on disk)", native, "compiled_library"),
            ("a sweep point's record (sensitivities, singular value)", Sweep, "_record"),
            ("static solves (a run's start)", Simulation, "solve"),
            ("residual evaluations (CasADi)", SquareSystem, "residual"),
            ("Jacobian evaluations (CasADi)", SquareSystem, "evaluate"),
            ("Jacobian evaluations (structured product)", StructuredJacobian, "__call__"),
            ("factorisations (SuperLU)", SquareSystem, "factorise"),
            ("factorisations in Newton (SuperLU)", SquareSystem, "_fresh_factors"),
            ("triangular solves (SuperLU)", OrderedLU, "solve"),
            ("chord steps in C (solver.jit)", NativeChord, "steps"),
            ("tangent predictor (studies)", SquareSystem, "predicted"),
            ("linearisations (a path's tangents, det J's sign)", SquareSystem, "linearise"),
            ("Newton's loop (Python)", SquareSystem, "newton"),
            ("Solution assembly (outputs, balance)", CollocationSolver, "_assemble"),
            ("step outputs without a Solution", CollocationSolver, "outputs"),
            ("energy account", EnergyAccount, "add")]


class StageProfile:
    """Wall time and calls per stage while the block runs (module docstring); a stage's time is
    its own, without the stages it calls (exclusive)."""

    def __init__(self):
        self.seconds, self.calls = defaultdict(float), defaultdict(int)
        self._saved = []
        self._children = []           # per active stage: the time of the stages it called

    def __enter__(self):
        for stage, owner, name in _targets():
            original = owner.__dict__[name]
            self._saved.append((owner, name, original))
            setattr(owner, name, self._timed(stage, original))
        return self

    def __exit__(self, *exc):
        for owner, name, original in reversed(self._saved):
            setattr(owner, name, original)
        self._saved = []
        return False

    def _timed(self, stage, function):
        profile = self

        def timed(*args, **kwargs):
            profile._children.append(0.0)
            started = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                elapsed = time.perf_counter() - started
                inner = profile._children.pop()
                profile.seconds[stage] += elapsed - inner
                profile.calls[stage] += 1
                if profile._children:
                    profile._children[-1] += elapsed
        return timed

    def report(self, total):
        """``{stage: {"s", "calls", "share"}}`` of a run of ``total`` seconds, and "other" for
        the rest."""
        out = {stage: {"s": s, "calls": self.calls[stage], "share": s / total} for stage, s in self.seconds.items()}
        rest = total - sum(self.seconds.values())
        out["other (Python between stages)"] = {"s": rest, "calls": 1, "share": rest / total}
        return out


def with_imports(report, seconds, total):
    """``report`` (:meth:`StageProfile.report` of a run of ``total`` seconds) with the imports
    before the run (``seconds``, counted in its "other") as a stage of their own."""
    out, other = dict(report), report["other (Python between stages)"]["s"] - seconds
    out["other (Python between stages)"] = {"s": other, "calls": 1, "share": other / total}
    out["imports (tca_casadi, CasADi, scipy)"] = {"s": seconds, "calls": 1, "share": seconds / total}
    return out


def print_stages(title, report, per=None):
    """Print a :meth:`StageProfile.report`, largest first; ``per``: (count, name) to also give
    each stage's time per item (e.g. per time step)."""
    print(title)
    for stage, row in sorted(report.items(), key=lambda item: -item[1]["s"]):
        each = f", {row['s'] / per[0] * 1e6:.0f} us per {per[1]}" if per else ""
        print(f"  {stage:<40s} {row['s']:8.3f} s {row['share']:6.1%}  ({row['calls']} calls{each})")
