"""The verdict's lead when a sign-defined effect fits far best with the impossible sign.

A backlash whose width fits negative (an approach that *leads* instead of
lagging) and lowers the cross-validated RMS far more than any plausible
candidate is not a footnote: the data's sign convention is likely reversed.
The lead says what the sign means (the parameter's ``sign`` words), the likely
causes and, for an effect driven by the approach directions, the option that
accepts the reversed convention (``--approach-sign reversed``).
"""
from __future__ import annotations

from doe_calib.diagnosis.candidate import effect_parameters, sizes_words
from doe_calib.model.effects import parse_effect

#: An implausible candidate leads the verdict when it removes this many times the
#: cross-validated RMS the best plausible one removes (or any, when none is material).
LEAD_FACTOR = 2.0

#: Why an effect driven by the approach directions fits with the impossible sign.
APPROACH_CAUSES = ("the approach directions are reversed (the file's approach1 … columns "
                   "follow the opposite convention), the rows are not in measurement order "
                   "(directions derived from the order are then wrong), or the joint readings "
                   "are link-side (an output encoder sees the band the other way)")


def wrong_signs(candidate, robot, registry=None) -> list:
    """(parameter, FittedSize) of the candidate's parameters whose fitted value has the sign
    their bounds forbid (a negative width)."""
    pars = {p.name: p for p in effect_parameters(candidate.spec, robot, registry)}
    out = []
    for size in candidate.sizes:
        p = pars.get(size.name)
        if p is not None and ((p.bounds[0] == 0 and size.value < 0)
                              or (p.bounds[1] == 0 and size.value > 0)):
            out.append((p, size))
    return out


def sign_lead(model, odd, proposed, cv, folds, words: str, registry=None) -> str:
    """The verdict's lead when ``odd`` (the best material candidate, physically implausible)
    fits far best with the impossible sign: what the sign means, the likely causes and the
    option that accepts the reversed convention ("" otherwise). ``proposed``: the best
    plausible material candidate or None; ``cv``: the model's cross-validated RMS, mm, over
    ``folds``; ``words``: ``odd`` in its effect's words."""
    wrong = wrong_signs(odd, model.robot, registry)
    best_gain = 0.0 if proposed is None else cv - proposed.cv_rms_mm
    if not wrong or cv - odd.cv_rms_mm < LEAD_FACTOR * best_gain:
        return ""
    effect = parse_effect(odd.spec, registry=registry)
    values = sizes_words(size for _, size in wrong)
    meaning = "; ".join(dict.fromkeys(p.sign for p, _ in wrong if p.sign))
    other = "" if proposed is None else \
        (f", against {100 * best_gain / cv:.0f} % for the best plausible candidate, "
         f"{proposed.spec}")
    text = (f"{words[0].upper()}{words[1:]} explains the data far better than any other "
            f"candidate, but with the impossible sign: adding {odd.spec} lowers the "
            f"cross-validated RMS {cv:.3g} mm ({folds.description}) to {odd.cv_rms_mm:.3g} mm "
            f"({100 * (1 - odd.cv_rms_mm / cv):.0f} %{other}), fitting {values}"
            + (f" ({meaning})" if meaning else "") + ".")
    if getattr(effect, "mode", None) in ("approach", "both"):
        loads = "" if effect.mode == "approach" else \
            "; in loaded poses, the load may be written with the opposite sign"
        text += (f" Likely causes: {APPROACH_CAUSES}{loads}. If the convention is reversed, rerun "
                 f"diagnose, refine or identify with --approach-sign reversed: {odd.spec} "
                 f"then fits a positive width.")
    else:
        text += (" Likely cause: the sign convention of what drives it (a load written as "
                 "the reaction, an axis reversed) is the opposite of the model's.")
    return text
