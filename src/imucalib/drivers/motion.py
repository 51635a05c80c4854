"""Rate tables and centrifuges on real controllers: ACUTROL (ACL) and Ideal Aerosmith (ASCII).

Both classes implement :class:`~imucalib.station.devices.MotionDevice`. A centrifuge is the same
class with one axis named ``"spin"``.

Contents
--------
:class:`AxisLimits`
    Software limits of one axis and, when known, the controller's absolute limits.
:class:`AcutrolTable`
    ACL over TCP (port 9878 on a real ACUTROL3000) or VISA (GPIB, ``TCPIP::…::SOCKET``).
:class:`AerosmithTable`
    The Ideal Aerosmith ASCII dialect over a serial line (or a serial server).

Safety (docs/drivers.md, "Sources": motion-layer safety)
--------------------------------------------------------
- Software limits (:class:`AxisLimits`) are checked **before** a demand is sent; a demand
  beyond them raises :class:`~imucalib.errors.LimitExceededError` naming the axis and the limit,
  and nothing goes to the controller. The controller's own profiler limits are set on connect.
- ``connect`` follows the safe sequence: ACL ``:U:L ON`` → ``:I:O <ax>`` → ``:I:R`` →
  ``:I:C <ax>`` → limits → ``:M:R <ax>`` → ``:D:R <ax>,0``; Aerosmith ``VEL``/``ACL`` →
  ``SRV1``.
- ``safe_stop`` never raises: ``:M:O ALL`` (Aerosmith ``STO``), wait until every axis is at rest
  (or `stop_timeout_s`), then ``:I:O ALL`` (``SRV0``). After a lost link it reconnects once and
  tries again.
- Any transport error drops the link (a late reply is never taken for the next answer);
  later commands raise :class:`~imucalib.errors.DeviceError` until ``connect`` (or
  ``safe_stop``) reopens it.
- Feedback rows are stamped with the station clock at the midpoint between the query and its
  reply; every command and reply is logged at debug level with its monotonic time.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from imucalib import units
from imucalib.drivers import acl, aerosmith
from imucalib.drivers.base import DeviceCheck, LineChannel, TransportOpener
from imucalib.errors import ConfigurationError, DeviceError, InvalidInputError, LimitExceededError
from imucalib.station.devices import AxisMode, Clock, MotionFeedback, MotionStatus

__all__ = ["AcutrolTable", "AerosmithTable", "AxisLimits"]

_LOG = logging.getLogger(__name__)


@dataclass(frozen=True)
class AxisLimits:
    """Limits of one axis.

    Parameters
    ----------
    max_rate_rps, max_accel_rps2 : float
        Software limits, checked before any demand is sent. [rad/s], [rad/s²]
    controller_max_rate_rps, controller_max_accel_rps2 : float, optional
        The controller's absolute limits ("limits on limits"), when known. [rad/s], [rad/s²]
    travel_rad : (float, float), optional
        Travel of a limited axis (None: unlimited rotation). [rad]
    """

    max_rate_rps: float
    max_accel_rps2: float
    controller_max_rate_rps: float | None = None
    controller_max_accel_rps2: float | None = None
    travel_rad: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for name in ("max_rate_rps", "max_accel_rps2"):
            v = float(getattr(self, name))
            if not math.isfinite(v) or v <= 0.0:
                raise ConfigurationError(f"`{name}` must be a finite number > 0; got {v}")


class _MotionDriver:
    """What the two dialects share: limits, time stamps, safe stop, status checks."""

    kind = "motion"
    role = "table"

    def __init__(self, name: str, axis_names: Sequence[str], channel: LineChannel, *,
                 clock: Clock, limits: Sequence[AxisLimits], address: str = "",
                 stop_timeout_s: float = 60.0, rest_rate_rps: float = 0.01 * units.DEG) -> None:
        self.name = name
        self.axis_names = tuple(axis_names)
        if not self.axis_names:
            raise ConfigurationError(f"{name}: a motion device needs at least one axis")
        if len(limits) != len(self.axis_names):
            raise ConfigurationError(f"{name}: {len(self.axis_names)} axes but {len(limits)} "
                                     "AxisLimits")
        self.limits = tuple(limits)
        self.address = address
        self._clock = clock
        self._ch = channel
        self.stop_timeout_s = float(stop_timeout_s)
        self.rest_rate_rps = float(rest_rate_rps)
        self._rate_limit = [lim.max_rate_rps for lim in self.limits]
        self._accel_limit = [lim.max_accel_rps2 for lim in self.limits]
        self._identity: str | None = None

    # --- checks -------------------------------------------------------------------------------
    def _axis(self, axis: int) -> int:
        if isinstance(axis, bool) or not isinstance(axis, int | np.integer) or \
                not 0 <= int(axis) < len(self.axis_names):
            raise InvalidInputError(f"{self.name}: axis must be an index 0–"
                                    f"{len(self.axis_names) - 1} ({', '.join(self.axis_names)}); "
                                    f"got {axis!r}")
        return int(axis)

    def _check_rate(self, i: int, rate_rps: float) -> float:
        rate = float(rate_rps)
        if not math.isfinite(rate):
            raise InvalidInputError(f"{self.name}: rate must be finite; got {rate_rps!r}")
        lim = self._rate_limit[i]
        if abs(rate) > lim * (1.0 + 1e-12):
            raise LimitExceededError(
                f"{self.name}: axis {self.axis_names[i]!r}: rate {rate / units.DEG:.6g} °/s "
                f"exceeds the software limit ±{lim / units.DEG:.6g} °/s; nothing was sent"
            )
        return rate

    def _check_angle(self, i: int, angle_rad: float) -> float:
        angle = float(angle_rad)
        if not math.isfinite(angle):
            raise InvalidInputError(f"{self.name}: angle must be finite; got {angle_rad!r}")
        travel = self.limits[i].travel_rad
        if travel is not None and not travel[0] <= angle <= travel[1]:
            raise LimitExceededError(
                f"{self.name}: axis {self.axis_names[i]!r}: angle {angle / units.DEG:.6g}° is "
                f"outside the travel [{travel[0] / units.DEG:.6g}, {travel[1] / units.DEG:.6g}]°; "
                "nothing was sent"
            )
        return angle

    def _check_limits(self, i: int, rate_rps: float, accel_rps2: float) -> tuple[float, float]:
        lim = self.limits[i]
        rate, acc = float(rate_rps), float(accel_rps2)
        for value, top, what, unit in ((rate, lim.max_rate_rps, "rate", "°/s"),
                                       (acc, lim.max_accel_rps2, "acceleration", "°/s²")):
            if not math.isfinite(value) or value <= 0.0:
                raise InvalidInputError(f"{self.name}: axis {self.axis_names[i]!r}: {what} "
                                        f"limit must be > 0; got {value / units.DEG:.6g} {unit}")
            if value > top * (1.0 + 1e-12):
                raise LimitExceededError(
                    f"{self.name}: axis {self.axis_names[i]!r}: {what} limit "
                    f"{value / units.DEG:.6g} {unit} exceeds the configured maximum "
                    f"{top / units.DEG:.6g} {unit}; nothing was sent"
                )
        return rate, acc

    def _send_limits(self, i: int, rate_rps: float, accel_rps2: float) -> None:
        raise NotImplementedError  # each dialect sends its own commands

    def set_limits(self, axis: int, *, rate_rps: float, accel_rps2: float) -> None:
        """Set an axis's rate and acceleration limits on the controller. [rad/s], [rad/s²]

        ACUTROL sets both profilers (position and rate); Aerosmith sends ``VEL`` and ``ACL``.

        Raises
        ------
        LimitExceededError
            If a value exceeds the configured maximum (nothing is sent).
        """
        i = self._axis(axis)
        rate, acc = self._check_limits(i, rate_rps, accel_rps2)
        self._send_limits(i, rate, acc)
        self._rate_limit[i], self._accel_limit[i] = rate, acc

    def _check_absolute(self, i: int, abs_rate_rps: float, abs_accel_rps2: float) -> None:
        """Refuse a configuration whose limits exceed what the controller reports."""
        lim = self.limits[i]
        for value, top, what, unit in ((lim.max_rate_rps, abs_rate_rps, "max_rate", "°/s"),
                                       (lim.max_accel_rps2, abs_accel_rps2, "max_accel",
                                        "°/s²")):
            if value > top * (1.0 + 1e-9):
                raise LimitExceededError(
                    f"{self.name}: axis {self.axis_names[i]!r}: configured {what} "
                    f"{value / units.DEG:.6g} {unit} exceeds the controller's absolute limit "
                    f"{top / units.DEG:.6g} {unit}"
                )

    # --- shared protocol methods --------------------------------------------------------------
    def open_link(self) -> None:
        """Open the link only: no lockout, no interlock, no mode change (for checks)."""
        self._ch.open()

    def identify(self) -> str:
        """Return the controller's identification string."""
        self._identity = self._query_identity()
        return self._identity

    def poll(self) -> MotionFeedback:
        """Return the current angles [rad] and rates [rad/s] of every axis (one row)."""
        t0 = self._clock.now_s()
        angles_deg, rates_dps = self._read_feedback()
        t1 = self._clock.now_s()
        k = len(self.axis_names)
        return MotionFeedback(np.array([0.5 * (t0 + t1)]),
                              np.asarray(angles_deg, dtype=np.float64).reshape(1, k) * units.DEG,
                              np.asarray(rates_dps, dtype=np.float64).reshape(1, k) * units.DEG)

    def safe_stop(self) -> None:
        """Bring every axis to rest, then switch the servos off; never raises."""
        for attempt in (1, 2):
            try:
                if not self._ch.is_open:
                    self._ch.open()
                self._stop_motion()
                self._wait_for_rest()
                self._servo_off()
                _LOG.info("%s: safe stop done", self.name)
                return
            except Exception as exc:  # the contract: never raise
                _LOG.warning("%s: safe stop, attempt %d: %s", self.name, attempt, exc)
                self._ch.close()
        _LOG.error("%s: safe stop could not reach the controller", self.name)

    def _wait_for_rest(self) -> None:
        deadline = self._clock.now_s() + self.stop_timeout_s
        while True:
            _, rates = self._read_feedback()
            if max(abs(r) for r in rates) * units.DEG <= self.rest_rate_rps:
                return
            if self._clock.now_s() > deadline:
                _LOG.warning("%s: not at rest after %g s (rates %s °/s); switching off anyway",
                             self.name, self.stop_timeout_s, rates)
                return
            self._clock.sleep(0.05)

    def check(self) -> DeviceCheck:
        """Open the link, identify, read status and one feedback row, close; moves nothing."""
        try:
            self.open_link()
            ident = self.identify()
            st = self.status()
            fb = self.poll()
        finally:
            self._ch.close()
        angles = ", ".join(f"{n} {a / units.DEG:.4f}°" for n, a in
                           zip(self.axis_names, fb.angle_rad[0], strict=True))
        rates = ", ".join(f"{r / units.DEG:.4f} °/s" for r in fb.rate_rps[0])
        modes = "/".join(st.modes)
        state = (f"modes {modes}; interlock {'closed' if st.interlock_closed else 'open'}"
                 + (f"; FAULT {st.fault}" if st.fault else ""))
        return DeviceCheck(self.role, self.name, self.kind, self.address, ident, state,
                           f"{angles}; rates {rates}", ok=st.fault is None,
                           details={"modes": list(st.modes), "fault": st.fault,
                                    "angle_rad": fb.angle_rad[0].tolist(),
                                    "rate_rps": fb.rate_rps[0].tolist()})

    def describe(self) -> dict[str, Any]:
        """Return a JSON-able description (kind, address, axes, limits, identity)."""
        return {
            "role": self.role, "name": self.name, "kind": self.kind, "address": self.address,
            "axes": list(self.axis_names), "identity": self._identity,
            "limits": [{"max_rate_dps": lim.max_rate_rps / units.DEG,
                        "max_accel_dps2": lim.max_accel_rps2 / units.DEG} for lim in self.limits],
        }

    # --- dialect hooks ------------------------------------------------------------------------
    def status(self) -> MotionStatus:  # pragma: no cover - abstract
        """Return the modes, the interlock state and any latched fault."""
        raise NotImplementedError

    def _query_identity(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def _read_feedback(self) -> tuple[list[float], list[float]]:  # pragma: no cover
        raise NotImplementedError

    def _stop_motion(self) -> None:  # pragma: no cover
        raise NotImplementedError

    def _servo_off(self) -> None:  # pragma: no cover
        raise NotImplementedError


# --- ACL ----------------------------------------------------------------------------------------
class AcutrolTable(_MotionDriver):
    """A rate table (or centrifuge) on an Acutronic ACUTROL controller, in the ACL dialect.

    Parameters
    ----------
    name : str
        Device name.
    axis_names : sequence of str
        Axis names, outer first (``("pitch", "roll")``; ``("spin",)`` for a centrifuge).
    opener : callable
        Returns an opened transport (TCP or VISA).
    clock : Clock
        The station clock, for feedback time stamps and waits.
    limits : sequence of AxisLimits
        One per axis.
    axis_numbers : sequence of int, optional
        Controller axis number of each axis (default 1, 2, …).
    timeout_s : float
        Reply time-out. [s]
    address : str
        Transport URL, for descriptions.
    stop_timeout_s : float
        Longest wait for rest in :meth:`safe_stop` (station-clock seconds). [s]
    role : str
        ``"table"`` or ``"centrifuge"`` (descriptions only).
    """

    kind = "acutrol"

    def __init__(self, name: str, axis_names: Sequence[str], opener: TransportOpener, *,
                 clock: Clock, limits: Sequence[AxisLimits],
                 axis_numbers: Sequence[int] | None = None, timeout_s: float = 2.0,
                 address: str = "", stop_timeout_s: float = 60.0, role: str = "table") -> None:
        channel = LineChannel(name, opener, terminator=acl.TERMINATOR, timeout_s=timeout_s,
                              logger=_LOG)
        super().__init__(name, axis_names, channel, clock=clock, limits=limits, address=address,
                         stop_timeout_s=stop_timeout_s)
        self.role = role
        nums = list(axis_numbers) if axis_numbers is not None else \
            list(range(1, len(self.axis_names) + 1))
        if len(nums) != len(self.axis_names) or len(set(nums)) != len(nums) or \
                any(n < 1 for n in nums):
            raise ConfigurationError(f"{name}: axis_numbers must be distinct integers ≥ 1, one "
                                     f"per axis; got {nums}")
        self.axis_numbers = tuple(int(n) for n in nums)
        self._modes: list[str | None] = [None] * len(self.axis_names)

    def _send(self, *commands: str, check: bool = True) -> acl.AclReply:
        line = self._ch.exchange(acl.join_commands(commands))[0]
        reply = acl.parse_reply(line)
        if check and not reply.ok:
            raise DeviceError(f"{self.name}: the controller refused {';'.join(commands)!r}: "
                              f"error {reply.code}: {reply.payload}")
        return reply

    def _query_identity(self) -> str:
        return self._send(acl.identify()).payload

    def connect(self) -> None:
        """Open the link, check the absolute limits, take control, close the interlocks.

        Raises
        ------
        LimitExceededError
            If a configured limit exceeds the controller's absolute limit (nothing is enabled).
        DeviceError
            If the controller refuses a step (e.g. a latched interlock fault).
        """
        self._ch.open()
        self.identify()
        for i, n in enumerate(self.axis_numbers):
            rate, acc = acl.parse_floats(self._send(acl.limit_absolute_query(n)), 2,
                                         f"absolute limits of axis {n}")
            self._check_absolute(i, rate * units.DEG, acc * units.DEG)
        self._send(acl.lockout(True))
        for n in self.axis_numbers:
            self._send(acl.interlock_open(n))
        self._send(acl.interlock_reset())
        for n in self.axis_numbers:
            self._send(acl.interlock_close(n))
        for i in range(len(self.axis_names)):
            self._send_limits(i, self._rate_limit[i], self._accel_limit[i])
        for i, n in enumerate(self.axis_numbers):
            self._send(acl.mode(n, "rate"), acl.demand_rate(n, 0.0))
            self._modes[i] = "rate"
        _LOG.info("%s: connected, interlocks closed, axes in rate mode at 0 °/s", self.name)

    def disconnect(self) -> None:
        """Release the remote lockout and close the link (call :meth:`safe_stop` first)."""
        try:
            if self._ch.is_open:
                self._send(acl.lockout(False), check=False)
        except DeviceError as exc:
            _LOG.warning("%s: releasing the lockout failed: %s", self.name, exc)
        finally:
            self._ch.close()
            self._modes = [None] * len(self.axis_names)

    def _send_limits(self, i: int, rate_rps: float, accel_rps2: float) -> None:
        n = self.axis_numbers[i]
        r, a = rate_rps / units.DEG, accel_rps2 / units.DEG
        self._send(acl.limit_rate("P", n, r), acl.limit_rate("R", n, r),
                   acl.limit_accel("P", n, a), acl.limit_accel("R", n, a))

    def move_to(self, axis: int, angle_rad: float) -> None:
        """Position mode: move an axis to an angle and hold it. [rad]"""
        i = self._axis(axis)
        angle = self._check_angle(i, angle_rad)
        n = self.axis_numbers[i]
        cmds = [] if self._modes[i] == "position" else [acl.mode(n, "position")]
        self._demand(i, "position", *cmds, acl.demand_position(n, angle / units.DEG))

    def set_rate(self, axis: int, rate_rps: float) -> None:
        """Rate mode: spin an axis at a constant rate. [rad/s]"""
        i = self._axis(axis)
        rate = self._check_rate(i, rate_rps)
        n = self.axis_numbers[i]
        cmds = [] if self._modes[i] == "rate" else [acl.mode(n, "rate")]
        self._demand(i, "rate", *cmds, acl.demand_rate(n, rate / units.DEG))

    def _demand(self, i: int, mode: str, *commands: str) -> None:
        """Send a demand; after a refusal, send the mode again next time."""
        try:
            self._send(*commands)
        except DeviceError:
            self._modes[i] = None
            raise
        self._modes[i] = mode

    def _read_feedback(self) -> tuple[list[float], list[float]]:
        k = len(self.axis_numbers)
        vals = acl.parse_floats(self._send(acl.read_feedback(self.axis_numbers)), 2 * k,
                                "feedback")
        return vals[:k], vals[k:]

    def status(self) -> MotionStatus:
        """Return modes, interlock state and the latched fault text (``:Q:E?``), if any."""
        nums = self.axis_numbers
        cmds = [acl.mode_query(n) for n in nums] + [acl.interlock_query(n) for n in nums]
        vals = self._send(*cmds).values()
        if len(vals) != 2 * len(nums):
            raise DeviceError(f"{self.name}: status: expected {2 * len(nums)} answers; got "
                              f"{vals}")
        mode_map: dict[str, AxisMode] = {"P": "position", "H": "position", "R": "rate",
                                         "A": "rate", "S": "rate", "T": "rate", "O": "off"}
        modes: list[AxisMode] = []
        for letter in vals[:len(nums)]:
            if letter.upper()[:1] not in mode_map:
                raise DeviceError(f"{self.name}: unknown mode answer {letter!r}")
            modes.append(mode_map[letter.upper()[:1]])
        locks = [v.upper() for v in vals[len(nums):]]
        fault = None
        if any(v.startswith("FAULT") for v in locks):
            code_txt = self._send(acl.status_csr("SI")).payload.strip()
            try:
                code = int(code_txt)
            except ValueError:
                code = -1
            text = self._send(acl.error_text(code), check=False).payload if code > 0 else ""
            fault = f"interlock fault {code}: {text}" if text else f"interlock fault {code_txt}"
        return MotionStatus(tuple(modes), all(v.startswith("CLOSED") for v in locks), fault)

    def _stop_motion(self) -> None:
        reply = self._send(acl.mode("ALL", "off"), check=False)
        if not reply.ok:
            _LOG.warning("%s: :M:O ALL answered error %d: %s", self.name, reply.code,
                         reply.payload)
        self._modes = ["off"] * len(self.axis_names)

    def _servo_off(self) -> None:
        reply = self._send(acl.interlock_open("ALL"), check=False)
        if not reply.ok:
            _LOG.warning("%s: :I:O ALL answered error %d: %s", self.name, reply.code,
                         reply.payload)


# --- Aerosmith ----------------------------------------------------------------------------------
class AerosmithTable(_MotionDriver):
    """A rate table (or centrifuge) on an Ideal Aerosmith controller, in its ASCII dialect.

    Parameters
    ----------
    name, axis_names, opener, clock, limits, timeout_s, address, stop_timeout_s, role
        As for :class:`AcutrolTable`.
    axis_prefix : bool, optional
        Prefix commands with the axis number (default: only with more than one axis;
        **[unverified]** convention, see :mod:`~imucalib.drivers.aerosmith`).
    """

    kind = "aerosmith"

    def __init__(self, name: str, axis_names: Sequence[str], opener: TransportOpener, *,
                 clock: Clock, limits: Sequence[AxisLimits], axis_prefix: bool | None = None,
                 timeout_s: float = 2.0, address: str = "", stop_timeout_s: float = 60.0,
                 role: str = "table") -> None:
        channel = LineChannel(name, opener, terminator=aerosmith.TERMINATOR, timeout_s=timeout_s,
                              logger=_LOG)
        super().__init__(name, axis_names, channel, clock=clock, limits=limits, address=address,
                         stop_timeout_s=stop_timeout_s)
        self.role = role
        self.axis_prefix = len(self.axis_names) > 1 if axis_prefix is None else bool(axis_prefix)

    def _prefix(self, i: int | None) -> int | None:
        return None if i is None or not self.axis_prefix else i + 1

    def _cmd(self, command: str, value: float | int | None = None, *, axis: int | None = None
             ) -> str:
        data = aerosmith.format_command(command, value, axis=self._prefix(axis))
        if not aerosmith.expects_reply(command):
            self._ch.send(data)
            return ""
        response, prompt = self._ch.exchange(data, lines=2)
        if prompt.strip() != aerosmith.PROMPT.encode():
            raise DeviceError(f"{self.name}: {command}: expected the prompt "
                              f"{aerosmith.PROMPT!r} after the response; got {prompt!r}")
        return aerosmith.parse_response(response, command)

    def _query_identity(self) -> str:
        return self._cmd("VER")

    def connect(self) -> None:
        """Open the link, set the velocity and acceleration limits, switch the servos on.

        Raises
        ------
        DeviceError
            If the controller refuses (e.g. a latched fault whose cause is still present).
        """
        self._ch.open()
        self.identify()
        for i in range(len(self.axis_names)):
            self._send_limits(i, self._rate_limit[i], self._accel_limit[i])
            self._cmd("SRV", 1, axis=i)
        _LOG.info("%s: connected, servos on", self.name)

    def disconnect(self) -> None:
        """Close the link (call :meth:`safe_stop` first)."""
        self._ch.close()

    def _send_limits(self, i: int, rate_rps: float, accel_rps2: float) -> None:
        self._cmd("VEL", rate_rps / units.DEG, axis=i)
        self._cmd("ACL", accel_rps2 / units.DEG, axis=i)

    def move_to(self, axis: int, angle_rad: float) -> None:
        """Absolute move (``MOV``) and hold. [rad]"""
        i = self._axis(axis)
        self._cmd("MOV", self._check_angle(i, angle_rad) / units.DEG, axis=i)

    def set_rate(self, axis: int, rate_rps: float) -> None:
        """Constant rate (``JOG``, which is not answered; ``STA`` confirms no fault). [rad/s]"""
        i = self._axis(axis)
        self._cmd("JOG", self._check_rate(i, rate_rps) / units.DEG, axis=i)
        st = aerosmith.parse_status(self._cmd("STA", axis=i))
        if st.fault is not None or not st.servo_on:
            raise DeviceError(f"{self.name}: axis {self.axis_names[i]!r}: JOG not running: "
                              f"servo {'on' if st.servo_on else 'off'}, fault {st.fault}")

    def _read_feedback(self) -> tuple[list[float], list[float]]:
        angles = [aerosmith.parse_number(self._cmd("PPO", axis=i), "PPO")
                  for i in range(len(self.axis_names))]
        rates = [aerosmith.parse_number(self._cmd("PVE", axis=i), "PVE")
                 for i in range(len(self.axis_names))]
        return angles, rates

    def status(self) -> MotionStatus:
        """Return modes (``STA``: OFF/POS/JOG/STOP), servo states and the first fault text."""
        sts = [aerosmith.parse_status(self._cmd("STA", axis=i))
               for i in range(len(self.axis_names))]
        mode_map: dict[str, AxisMode] = {"OFF": "off", "POS": "position", "JOG": "rate",
                                         "STOP": "stop"}
        faults = [f"axis {self.axis_names[i]!r}: {s.fault}" for i, s in enumerate(sts)
                  if s.fault]
        return MotionStatus(tuple(mode_map[s.mode] for s in sts), all(s.servo_on for s in sts),
                            "; ".join(faults) or None)

    def _each_axis(self, command: str, value: int | None = None) -> None:
        for i in range(len(self.axis_names)):
            try:
                self._cmd(command, value, axis=i)
            except DeviceError as exc:
                if not self._ch.is_open:
                    raise
                _LOG.warning("%s: %s: %s", self.name, command, exc)

    def _stop_motion(self) -> None:
        self._each_axis("STO")

    def _servo_off(self) -> None:
        self._each_axis("SRV", 0)
