"""The marker labels the models read, the other spellings labs use for them, and what a
model version needs.

Labs label the same anatomical markers in more than one way: older Vicon Workstation and
Clinical Manager sessions call the sacrum marker ``VSAC`` where Plug-in Gait's current
templates say ``SACR``, and labelling by hand in another program gives ``lasi`` for
``LASI``.  :func:`canonical_labels` renames such labels to the models' names (only when the
model's own name is absent, so nothing is ever overwritten) and says what it renamed.
"""

from __future__ import annotations

from dataclasses import replace

from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.core.trial import Trial

#: Per side, the markers of Plug-in Gait's lower body (HEE: foot virtual markers, events).
PIG_SIDE_MARKERS: tuple[str, ...] = ("THI", "KNE", "TIB", "ANK", "TOE", "HEE")
#: Per side, the markers of a static trial's options and of the CGM 2.x clusters/forefoot.
OPTION_SIDE_MARKERS: tuple[str, ...] = ("KAX", "KD1", "KD2", "KNM", "MED", "THAP", "THAD", "TIAP", "TIAD",
                                        "FMH", "SMH", "VMH")  # fmt: skip
#: The pelvis markers: both ASIS and the sacrum or both PSIS.
PELVIS_MARKERS: tuple[str, ...] = ("LASI", "RASI", "SACR", "LPSI", "RPSI")
#: Every label a model reads.
MODEL_LABELS: frozenset[str] = frozenset(
    PELVIS_MARKERS + tuple(side + name for side in "LR" for name in PIG_SIDE_MARKERS + OPTION_SIDE_MARKERS)
)
#: Other labels of a model marker, by the model's label: ``VSAC`` (the sacrum of older
#: Vicon Workstation / Clinical Manager marker sets).
MARKER_ALIASES: dict[str, tuple[str, ...]] = {"SACR": ("VSAC",)}
_ALIAS_OF = {alias: name for name, aliases in MARKER_ALIASES.items() for alias in aliases}


def canonical_name(label: str) -> str | None:
    """The model label ``label`` stands for (an alias, or the label in another letter
    case), or None when it is none of them or already the model's own."""
    if label in MODEL_LABELS:
        return None
    upper = label.upper()
    if upper in _ALIAS_OF:
        return _ALIAS_OF[upper]
    return upper if upper in MODEL_LABELS else None


def canonical_labels(trial: Trial) -> tuple[Trial, list[Finding]]:
    """``trial`` with the aliases of model markers renamed to the model's labels (when
    the model's label is not there already), and a note saying which; unchanged and no
    note when nothing is renamed."""
    present = set(trial.marker_labels)
    renames: dict[str, str] = {}
    for label in trial.marker_labels:
        target = canonical_name(label)
        if target is not None and target not in present and target not in renames.values():
            renames[label] = target
    if not renames:
        return trial, []
    labels = [renames.get(label, label) for label in trial.marker_labels]
    listed = ", ".join(f"{old} as {new}" for old, new in renames.items())
    note = Finding(FindingKind.MARKER_LABELS, f"marker labels read as the model's: {listed}")
    return replace(trial, marker_labels=labels), [note]


def required_markers(clusters: bool, forefoot: bool) -> str:
    """What a model version's marker set needs, in words (for error lines)."""
    side = ", ".join(PIG_SIDE_MARKERS[:5])
    text = f"LASI, RASI and SACR (or LPSI and RPSI); per side {side}"
    if clusters:
        text += ", THAP, THAD, TIAP, TIAD (the static trial also KNM, MED)"
    if forefoot:
        text += ", FMH, SMH, VMH"
    return text
