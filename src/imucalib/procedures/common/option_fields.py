"""The options many procedures share, declared once: each a function returning its field.

A procedure's options dataclass (``procedures/<name>/options.py``) writes, for an option every
twin plan has, ``grade: Grade = grade_field("tactical")`` instead of repeating its help, unit
and range; only the default (and, where the procedure means more by it, the help) differs.
Each function returns :func:`~imucalib.procedures.common.options.option`'s field.

Contents
--------
:data:`Grade`, :data:`TwinNoise`, :func:`grade_field`, :func:`sample_rate_field`,
:func:`seed_field`, :func:`latitude_field`, :func:`twin_noise_field`, :func:`errors_field`,
:func:`twin_field`, :func:`plan_name_field`, :func:`record_field`, :func:`settle_field`,
:func:`warm_up_field`, :func:`gravity_field`, :func:`noise_block_field`,
:func:`max_lost_fraction_field`, :func:`max_gap_field`, :data:`TermCriterion`,
:func:`terms_field`, :func:`term_criterion_field`, :func:`term_level_field`
"""

from __future__ import annotations

from typing import Any, Literal

from imucalib.plan.bounds import (
    MAX_RECORD_S,
    MAX_SAMPLE_RATE_HZ,
    MAX_SETTLE_S,
    MAX_WAIT_S,
    MIN_SAMPLE_RATE_HZ,
)
from imucalib.procedures.common.options import option

__all__ = ["Grade", "TermCriterion", "TwinNoise", "errors_field", "grade_field", "gravity_field",
           "latitude_field", "max_gap_field", "max_lost_fraction_field", "noise_block_field",
           "plan_name_field", "record_field", "sample_rate_field", "seed_field", "settle_field",
           "term_criterion_field", "term_level_field", "terms_field", "twin_field",
           "twin_noise_field", "warm_up_field"]

#: The IMU grades a plan accepts.
Grade = Literal["consumer", "tactical", "navigation"]
#: The twin IMU's noise: the grade's full model, or white noise only.
TwinNoise = Literal["grade", "white"]
#: How the data choose a fit's optional model terms (estimation/term_selection.py).
TermCriterion = Literal["lrt", "aicc", "bic"]

_TWIN_EDIT = "edit the plan's [twin] table instead"


def grade_field(default: str, *,
                help: str = "The IMU's grade (the twin's IMU and the default warm-up).") -> Any:
    """Return the ``grade`` field (the twin group)."""
    return option(default, help=help, group="twin")


def sample_rate_field(default: float, *, help: str = "The twin IMU's output rate.") -> Any:
    """Return the ``sample_rate_hz`` field [Hz] (the twin group)."""
    return option(default, help=help, unit="Hz", min=MIN_SAMPLE_RATE_HZ,
                  max=MAX_SAMPLE_RATE_HZ, group="twin")


def seed_field(default: int) -> Any:
    """Return the ``seed`` field (the twin group)."""
    return option(default, help="Seed of the twin (the IMU's truth and noise).",
                  min=-(2**63), max=2**63 - 1, group="twin")


def latitude_field(default: float = 45.0) -> Any:
    """Return the twin site's ``latitude_deg`` field [°]."""
    return option(default, help="Latitude of the twin's site.", unit="°", min=-90.0,
                  max=90.0, group="twin")


def twin_noise_field(default: str = "grade") -> Any:
    """Return the twin IMU's ``noise`` field."""
    return option(default, help="The twin IMU's noise (the grade's full model, or white only).",
                  group="twin")


def errors_field() -> Any:
    """Return the Python-only ``errors`` field: the twin IMU's known truth values."""
    return option(None, help="Known truth values of the twin IMU (SI).", group="twin",
                  python_only="a mapping of truth values; pass it from Python or edit the "
                              "errors of the plan's [twin] IMU")


def twin_field(help: str = "Another twin station.") -> Any:
    """Return the Python-only ``twin`` field: another twin station."""
    return option(None, help=help, group="twin",
                  python_only=f"a TwinEquipment object; {_TWIN_EDIT}")


def plan_name_field(default: str) -> Any:
    """Return the plan's ``name`` field (the plan group)."""
    return option(default, help="The plan's name (the recording's file name starts with it).",
                  group="plan")


def record_field(default: float, *, help: str = "Record at each position.",
                 min: float = 0.0) -> Any:
    """Return a ``record_s`` field [s] (the timing group)."""
    return option(default, help=help, unit="s", min=min, max=MAX_RECORD_S, group="timing")


def settle_field(default: float, *, help: str = "Settling before each record.") -> Any:
    """Return a ``settle_s`` field [s] (the timing group)."""
    return option(default, help=help, unit="s", min=0.0, max=MAX_SETTLE_S, group="timing")


def warm_up_field(help: str = "Warm-up (the grade's 15, 30 or 60 min when omitted).") -> Any:
    """Return the ``warm_up_s`` field [s] (the timing group; None: the grade's)."""
    return option(None, help=help, unit="s", min=0.0, max=MAX_WAIT_S, group="timing")


def gravity_field(help: str = "Local gravity (default: normal gravity at the recorded "
                              "latitude).") -> Any:
    """Return the analysis's ``gravity_mps2`` field [m/s²] (None: normal gravity)."""
    return option(None, help=help, unit="m/s²", min=0.0)


def noise_block_field(default: float,
                      help: str = "The block length of the white-noise estimate.") -> Any:
    """Return the analysis's ``noise_block_s`` field [s]."""
    return option(default, help=help, unit="s", min=0.0, group="timing")


def max_lost_fraction_field(default: float) -> Any:
    """Return the rate windows' ``max_lost_fraction`` field."""
    return option(default, help="The fraction of a window's expected samples that dropouts may "
                                "take.", min=0.0, max=1.0)


def max_gap_field(default: float) -> Any:
    """Return the rate windows' ``max_gap_s`` field [s]."""
    return option(default, help="The longest single dropout in a window.", unit="s", min=0.0,
                  group="timing")


def terms_field(help: str) -> Any:
    """Return a ``terms`` field: model terms forced in or out (``"+k2,-g"``).

    `help` names the procedure's terms; the others are chosen by the data
    (:func:`~imucalib.estimation.term_selection.choose_terms`).
    """
    return option("", help=help)


def term_criterion_field(doc: str) -> Any:
    """Return the ``term_criterion`` field (default: the likelihood-ratio test; `doc` the page)."""
    return option("lrt", help="How the data choose the terms: a likelihood-ratio test at "
                              f"term_level, AICc or BIC ({doc}, \"Model terms\").")


def term_level_field() -> Any:
    """Return the ``term_level`` field: α of the likelihood-ratio test (default 5 %)."""
    return option(0.05, help="The likelihood-ratio test's level α.", min=1e-9, max=0.5)
