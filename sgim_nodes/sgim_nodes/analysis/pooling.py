"""Pool only what is alike: the learner fingerprints of a study's runs, compared before any
figure or table.

Why: a comparison of learners is only worth what its runs are. Runs of two commits, two numpy
versions or two worlds are samples of different experiments, and a run resumed by another
learner is not one learner's run at all; pooling them would look like one study and be none.
The settings that tell groups apart (teacher, budget, parameters) already split a learner's
runs into groups (study.group_runs); the fingerprint's ``parameters`` field must then agree
within each group, since it also covers the node parameters that metadata does not list.
Runs made before fingerprints cannot be shown alike, so they are refused too. Each refusal
names the field and which runs hold which value; ``--allow-mixed`` pools them anyway and the
report says so at its top.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from sgim_nodes.analysis.study import RunData, Study
from sgim_nodes.provenance.fingerprint import (
    ENVIRONMENT_FIELDS,
    Fingerprint,
    canonical,
    parameter_differences,
)

NONE = "none"
SHOWN_NAMES = 3  # run names shown per value; the rest are counted


@dataclass(frozen=True)
class Unlike:
    """One way the runs are not alike: ``what`` differs (a fingerprint field, "fingerprint"
    when some runs have none, "resumed", or a group's parameters), and which runs hold each
    value (value -> run names, the most common value first)."""

    what: str
    holders: Mapping[str, list[str]] = field(default_factory=dict)

    def describe(self) -> str:
        """'numpy: 2.4.6 in 40 runs (sgim-d-seed0, ...), 1.26.4 in 10 runs (...)'."""
        parts = []
        for value, names in self.holders.items():
            shown = ", ".join(names[:SHOWN_NAMES]) + (", ..." if len(names) > SHOWN_NAMES
                                                      else "")
            parts.append(f"{value} in {len(names)} run{'s' if len(names) != 1 else ''} "
                         f"({shown})")
        return f"{self.what}: " + ", ".join(parts)


class MixedRunsError(ValueError):
    """The runs to be pooled are not alike (the message names how); see unlike_runs."""


def run_fingerprint(run: RunData) -> Fingerprint | None:
    """The learner fingerprint recorded in the run's metadata (None: made before them)."""
    return Fingerprint.from_dict(run.metadata.get("fingerprint"))


def _holders(values: Mapping[str, str]) -> dict[str, list[str]]:
    """run name -> value, as value -> run names, the most common value first."""
    out: dict[str, list[str]] = {}
    for name in sorted(values):
        out.setdefault(values[name], []).append(name)
    return dict(sorted(out.items(), key=lambda kv: -len(kv[1])))


def _find(parameters: Mapping[str, Any], name: str) -> Any:
    """A parameter's value in a (possibly nested by node) mapping; the first found."""
    if name in parameters and not isinstance(parameters[name], Mapping):
        return parameters[name]
    for value in parameters.values():
        if isinstance(value, Mapping):
            found = _find(value, name)
            if found is not None:
                return found
    return None


def _parameters_unlike(group: str, prints: dict[str, Fingerprint]) -> Unlike | None:
    """Runs of one group whose fingerprint ``parameters`` differ, named by parameter."""
    digests = {name: fp.fields.get("parameters", "") for name, fp in prints.items()}
    if len(set(digests.values())) < 2:
        return None
    by_digest = _holders(digests)
    reference = prints[next(iter(by_digest.values()))[0]]
    names = sorted({n for runs in by_digest.values()
                    for n in parameter_differences(reference.parameters,
                                                   prints[runs[0]].parameters)})
    holders = {}
    for digest, runs in by_digest.items():
        params = prints[runs[0]].parameters
        shown = ", ".join(f"{n}={canonical(_find(params, n))}" for n in names
                          if not n.startswith("node "))
        holders[shown or f"parameters {digest}"] = runs
    return Unlike(f"parameters of '{group}' ({', '.join(names) or 'unnamed'})", holders)


def unlike_runs(study: Study) -> list[Unlike]:
    """Every way the study's runs are not alike, empty when they may be pooled: fingerprints
    missing (from all runs or some), an environment field that differs across the study, a
    run resumed by another learner, or a group whose runs differ in their learner's own code
    or their parameters."""
    runs = sorted(study.runs, key=lambda r: r.name)
    prints = {r.name: run_fingerprint(r) for r in runs}
    found = {name: fp for name, fp in prints.items() if fp is not None}
    out: list[Unlike] = []
    if len(found) < len(prints):
        out.append(Unlike("fingerprint", _holders({
            name: "recorded" if fp else f"{NONE} (made before learner fingerprints)"
            for name, fp in prints.items()})))
    for key in ENVIRONMENT_FIELDS:
        values = {name: fp.fields.get(key, NONE) for name, fp in found.items()}
        if len(set(values.values())) > 1:
            out.append(Unlike(key, _holders(values)))
    resumed: dict[str, str] = {}
    for run in runs:
        changed = [f"{e.get('segment', '?')} changed "
                   + ", ".join(map(str, e["fingerprint_changed"]))
                   for e in run.metadata.get("resumed") or []
                   if isinstance(e, Mapping) and e.get("fingerprint_changed")]
        if changed:
            resumed[run.name] = "; ".join(changed)
    if resumed:
        out.append(Unlike("resumed by another learner", _holders(resumed)))
    for group in study.learners:
        members = {r.name: found[r.name] for r in study.runs_of(group) if r.name in found}
        own_code = {name: fp.fields.get("learner_code", NONE) for name, fp in members.items()}
        if len(set(own_code.values())) > 1:
            out.append(Unlike(f"learner_code of '{group}'", _holders(own_code)))
        unlike = _parameters_unlike(group, members)
        if unlike:
            out.append(unlike)
    return out


def predates_fingerprints(study: Study, unlike: Sequence[Unlike]) -> bool:
    """Whether no run of the study has a fingerprint (a study made before them)."""
    return bool(study.runs) and all(run_fingerprint(r) is None for r in study.runs) \
        and any(u.what == "fingerprint" for u in unlike)


def refusal(study: Study, unlike: Sequence[Unlike]) -> str:
    """The message that refuses to pool: what differs, which runs hold what, the way out."""
    if predates_fingerprints(study, unlike):
        head = (f"the {len(study.runs)} runs predate learner fingerprints: nothing shows they "
                "were made by one learner in one environment.")
        rest = [u for u in unlike if u.what != "fingerprint"]
    else:
        head, rest = "the runs are not alike, so pooling them would mix experiments:", unlike
    lines = [head, *(f"  {u.describe()}" for u in rest)]
    lines.append("Analyse like runs apart, make the odd ones again, or pass --allow-mixed to "
                 "pool them anyway (the results then say so at their top).")
    return "\n".join(lines)


def mixed_note(unlike: Sequence[Unlike]) -> str:
    """The line that heads a report of mixed runs (--allow-mixed)."""
    return ("**Mixed runs pooled (--allow-mixed)**: "
            + "; ".join(u.describe() for u in unlike) + ".")


def check_alike(study: Study, allow_mixed: bool = False) -> list[Unlike]:
    """The ways the runs differ; raises MixedRunsError unless ``allow_mixed``."""
    unlike = unlike_runs(study)
    if unlike and not allow_mixed:
        raise MixedRunsError(refusal(study, unlike))
    return unlike
