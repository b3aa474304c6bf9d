"""Plain-text summaries of trials for the terminal (``fuzzygait info``)."""

from __future__ import annotations

from collections import Counter

from fuzzygait.core.trial import Trial
from fuzzygait.mocap.gap_plan import find_gaps

_MAX_LISTED = 12  # markers listed by name before "... and N more"


def _listing(names: list[str]) -> str:
    head = ", ".join(names[:_MAX_LISTED])
    return head + (f", ... and {len(names) - _MAX_LISTED} more" if len(names) > _MAX_LISTED else "")


def describe_gaps(trial: Trial) -> list[str]:
    """One line per marker with gaps: count, total missing frames and longest gap."""
    lines = []
    missing = trial.missing_mask()
    for column, label in enumerate(trial.marker_labels):
        runs = find_gaps(missing[:, column])
        if not runs:
            continue
        total = sum(r.length for r in runs)
        if total == trial.n_frames:
            lines.append(f"{label}: never visible")
            continue
        longest = max(r.length for r in runs)
        lines.append(
            f"{label}: {len(runs)} gap{'s' if len(runs) > 1 else ''}, "
            f"{total} frames missing, longest {longest}"
        )
    return lines


def describe_events(trial: Trial) -> list[str]:
    """Events grouped by context and label, with their times in seconds."""
    grouped: dict[tuple[str, str], list[float]] = {}
    for event in trial.events:
        grouped.setdefault((event.context, event.label), []).append(event.time)
    return [
        f"{context} {label} x{len(times)}: " + ", ".join(f"{t:.3f}" for t in times) + " s"
        for (context, label), times in grouped.items()
    ]


def describe_trial(trial: Trial) -> str:
    """A multi-line summary: rate, frames, markers, outputs, events, gaps, parameters."""
    last = trial.first_frame + trial.n_frames - 1
    duration = trial.n_frames / trial.rate
    lines = [
        f"{trial.name}",
        f"  rate {trial.rate:g} Hz, {trial.n_frames} frames ({trial.first_frame}-{last}, "
        f"{duration:.2f} s), marker units mm",
        f"  {trial.n_markers} markers: {_listing(trial.marker_labels)}",
    ]
    if trial.outputs:
        kinds = Counter(trial.output_kinds[name] for name in trial.outputs)
        lines.append(
            f"  {len(trial.outputs)} model outputs: "
            + ", ".join(f"{count} {kind.replace('_', ' ')}" for kind, count in sorted(kinds.items()))
        )
    if trial.subject or trial.label_prefix:
        prefix = f" (label prefix {trial.label_prefix!r} removed)" if trial.label_prefix else ""
        lines.append(f"  subject {trial.subject or '?'}{prefix}")
    lines.append(f"  subject parameters: {len(trial.parameters)}" + (
        " (" + _listing(list(trial.parameters)) + ")" if trial.parameters else ""
    ))
    events = describe_events(trial)
    lines.append("  events:" + (" none" if not events else ""))
    lines += [f"    {line}" for line in events]
    gaps = describe_gaps(trial)
    lines.append(f"  gaps: {'none' if not gaps else f'{len(gaps)} markers'}")
    lines += [f"    {line}" for line in gaps]
    lines += [f"  note: {note.message}" for note in trial.notes]
    return "\n".join(lines)
