"""The protocols a procedure implements: :class:`Procedure` and :class:`ProcedureResult`.

A procedure is a folder of :mod:`imucalib.procedures` (``p1/``, ``allan/``, …) whose ``roles``
module names its step roles (:attr:`Procedure.roles`) and whose ``procedure`` module holds one
object satisfying :class:`Procedure`, registered by name in
:mod:`imucalib.procedures.registry`. ``imucalib plan new``, ``imucalib calibrate``, the demo and
the tests reach a procedure only through the registry; the output files of its result are named
and written by :func:`imucalib.exports.outputs.write_outputs`. A procedure also presents its
result, with code kept in its own folder: its report's sections 1–5
(:meth:`Procedure.report_content`), the terminal (:meth:`Procedure.render_console`) and a
batch's summary report (:meth:`Procedure.summary_report`); the report and terminal frameworks
(:mod:`imucalib.report`) name no procedure, and a procedure without presentation of its own
delegates to the generic one (:class:`~imucalib.procedures.common.reporting.GenericReporting`).
A procedure may also predict its result's uncertainty from a plan before it runs: the optional
``predict(plan) -> Prediction`` of :class:`~imucalib.procedures.common.prediction.Predicting`
(``imucalib plan show PLAN --predict``, docs/test-design.md); it is not part of
:class:`Procedure`, so a procedure without it still satisfies the protocol.
docs/procedures.md says how to add one.

Contents
--------
:class:`Procedure`, :func:`accepted_options`; :class:`ProcedureResult`, the result contract,
is :mod:`imucalib.models.procedure_result`'s (re-exported here).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from imucalib.errors import InvalidInputError
from imucalib.models.procedure_result import ProcedureResult

if TYPE_CHECKING:
    from rich.console import Console

    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.report.document import ReportContent, ReportDocument

__all__ = ["OutputWriter", "Procedure", "ProcedureResult", "accepted_options"]

#: A procedure's writer of one output format: (result, folder, file stem) → the paths written.
OutputWriter = Callable[[Any, Path, str], list[Path]]


@runtime_checkable
class Procedure(Protocol):
    """One calibration or characterisation procedure: its plan, its analysis, its presentation.

    Attributes
    ----------
    name : str
        Registry name; also the plan's ``procedure`` field and the prefix of its step roles
        (``"p1.accel-position"``).
    description : str
        One line for listings.
    roles : mapping of str to str
        The step roles of its plans and analysis, each ``"<name>.<purpose>"``
        (:func:`~imucalib.io.step_roles.split_role`), with what a step of that role is for (one
        line); a built-in's come from its folder's ``roles.py``. A step file's roles are checked
        against them (:func:`~imucalib.procedures.registry.check_roles`); ``imucalib procedures
        NAME`` lists them.
    plan_options_type : type
        The frozen dataclass whose fields are :meth:`generate_plan`'s keywords, each made by
        :func:`~imucalib.procedures.common.options.option` (help, unit, range, help section,
        or why the command line cannot give it); ``imucalib plan new NAME`` builds its flags
        and its ``--help`` from it.
    plan_options : frozenset of str
        The keywords :meth:`generate_plan` takes: the fields of :attr:`plan_options_type`
        (:func:`~imucalib.procedures.common.options.option_names`).
    analysis_options_type : type
        The frozen dataclass whose fields are the keys :meth:`analyze` accepts in `options`,
        each made by :func:`~imucalib.procedures.common.options.option` (help, unit, range,
        help section, or why the command line cannot give it); ``imucalib calibrate`` reads them
        with ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    analysis_options : frozenset of str
        The keys :meth:`analyze` accepts in `options` (P1: ``model``): the fields of
        :attr:`analysis_options_type` (:func:`~imucalib.procedures.common.options.option_names`).
    outputs : tuple of str
        The output formats of its result that :func:`~imucalib.exports.outputs.write_outputs`
        writes by default, in order (:data:`~imucalib.exports.outputs.OUTPUT_FORMATS`).
    """

    @property
    def name(self) -> str:
        """Registry name."""
        ...

    @property
    def description(self) -> str:
        """One line for listings."""
        ...

    @property
    def roles(self) -> Mapping[str, str]:
        """Step role → what a step of that role is for."""
        ...

    @property
    def plan_options_type(self) -> type:
        """The dataclass of :meth:`generate_plan`'s keywords."""
        ...

    @property
    def plan_options(self) -> frozenset[str]:
        """Keywords of :meth:`generate_plan` (the fields of :attr:`plan_options_type`)."""
        ...

    @property
    def analysis_options_type(self) -> type:
        """The dataclass of the keys :meth:`analyze` accepts."""
        ...

    @property
    def analysis_options(self) -> frozenset[str]:
        """Keys :meth:`analyze` accepts (the fields of :attr:`analysis_options_type`)."""
        ...

    @property
    def outputs(self) -> tuple[str, ...]:
        """Default output formats, in order."""
        ...

    def generate_plan(self, **options: Any) -> Plan:
        """Return the procedure's default plan (keyword options: its generator's)."""
        ...

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> ProcedureResult:
        """Analyse a recording of this procedure's plan.

        For one IMU (`unit`; the only one when omitted), with the procedure's `options` (keys in
        :attr:`analysis_options`). `progress`, when given, is called with the fraction of the
        work done (increasing, ending at 1.0), for a progress bar; it must not raise.
        """
        ...

    def report_content(self, result: ProcedureResult, meta: Mapping[str, Any]) -> ReportContent:
        """Return sections 1–5 of the report (certificate) of one unit's result.

        The report's object, equipment, environment, process and results sections
        (docs/reporting.md); :func:`imucalib.report.document.assemble_report` adds the
        conclusion and the appendix. Called through the registry by
        :func:`imucalib.exports.report.build_report` (``report-pdf``, ``report-html``,
        ``imucalib report``).

        Parameters
        ----------
        result : ProcedureResult
            What :meth:`analyze` returned for one unit (one unit of a batch), or a result read
            back from its JSON file (a ``CalibrationResult`` as its ``result``).
        meta : mapping of str to object
            The facts of the recording analysed
            (:func:`imucalib.report.sections.recording_facts`): its metadata, temperatures,
            file name and SHA-256; empty when no recording is given.

        Returns
        -------
        ReportContent
            The sections, the decision in words, the recommendations and the provenance. A
            procedure without content of its own returns the generic
            :func:`imucalib.report.content_generic.content`: every parameter of its
            ``parameter_rows()`` with U = 2u.

        Raises
        ------
        InvalidInputError
            A result the report cannot describe (no parameter rows).
        """
        ...

    def render_console(self, console: Console, result: ProcedureResult,
                       written: Sequence[Path]) -> None:
        """Print a result of :meth:`analyze` on the terminal.

        For ``imucalib calibrate``, ``imucalib allan`` and the demo, after the output files are
        written. A procedure without a table of its own calls
        :func:`imucalib.report.console.render_generic` (its ``parameter_rows()``, decision and
        files).

        Parameters
        ----------
        console : rich.console.Console
            Where to print.
        result : ProcedureResult
            What :meth:`analyze` returned (a batch for P2).
        written : sequence of Path
            The files written, listed last.
        """
        ...

    def output_writers(self) -> Mapping[str, OutputWriter]:
        """Return the output formats this procedure writes itself, by format name.

        :func:`~imucalib.exports.outputs.write_outputs` writes the formats every result has
        (:data:`~imucalib.exports.outputs.OUTPUT_FORMATS`: result JSON, parameters CSV,
        intrinsics, reports) and these (Allan: the noise YAML, tables and figures; P1: the
        residual figure; P2: the temperature figure). A writer takes (result, folder, file
        stem) and returns the paths it wrote; none by default
        (:class:`~imucalib.procedures.common.defaults.ProcedureDefaults`).
        """
        ...

    def batch_outputs(self, batch: ProcedureResult, folder: Path, stem: str) -> list[Path]:
        """Write a batch's own files after its members' (P2: the lot's summary and figure).

        Called by :func:`~imucalib.exports.outputs.write_outputs` for a result with
        ``members``; `stem` is ``<name>.<batch unit>.<procedure>``. None by default.
        """
        ...

    def analyze_many(self, recordings: Sequence[Recording | str | os.PathLike[str]], *,
                     units: Sequence[str] | None = None,
                     options: Mapping[str, Any] | None = None,
                     progress: Callable[[float], None] | None = None) -> ProcedureResult:
        """Analyse several recordings as one: a production lot (P2: one cube per recording).

        :func:`imucalib.calibration.calibrate` calls it for ``imucalib calibrate REC MORE…``;
        a procedure that analyses one recording at a time refuses
        (:class:`~imucalib.procedures.common.defaults.ProcedureDefaults`).

        Raises
        ------
        InvalidInputError
            The procedure analyses one recording at a time.
        """
        ...

    def summary_report(self, batch: ProcedureResult, *,
                       recordings: Sequence[Any] | None = None,
                       report_ids: Mapping[str, str] | None = None) -> ReportDocument:
        """Return the summary report of a batch: every unit's result in one document.

        For a procedure whose :meth:`analyze` returns a batch (a result with ``results``, one
        per unit: P2's array or lot), beside each unit's own report. Called through the registry
        by :func:`imucalib.exports.report.build_summary_report`.

        Parameters
        ----------
        batch : ProcedureResult
            The batch :meth:`analyze` returned.
        recordings : sequence of Recording or path, optional
            The recordings analysed, for the environment section.
        report_ids : mapping of str to str, optional
            Each unit's report id as issued; default: the id of the unit's result.

        Returns
        -------
        ReportDocument

        Raises
        ------
        InvalidInputError
            The procedure returns no batch
            (:func:`imucalib.report.document.no_summary_report`).
        """
        ...


def accepted_options(procedure: str, options: Mapping[str, Any] | None,
                     allowed: frozenset[str]) -> dict[str, Any]:
    """Return `options` as a dict, refusing a key `procedure`'s analysis does not take.

    Raises
    ------
    InvalidInputError
        An unknown option (the message lists those the procedure takes).
    """
    opts = dict(options or {})
    unknown = sorted(set(opts) - allowed)
    if unknown:
        raise InvalidInputError(f"procedure {procedure} takes the option(s) {sorted(allowed)}; "
                                f"got {unknown}")
    return opts
