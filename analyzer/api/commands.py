"""``COMMANDS``: the command table as integrators read it, physical units and ranges.

>>> from analyzer import COMMANDS
>>> [c.name for c in COMMANDS if c.component == "dual_sensor"]
... # doctest: +NORMALIZE_WHITESPACE
['tap_zoom', 'palette', 'pip_cycle', 'gimbal_control', 'tracking', 'tracking_stop',
 'digital_zoom']
"""

from __future__ import annotations

from dataclasses import dataclass

from analyzer.protocol import command_table
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import COMPONENT_NAMES

__all__ = ["COMMANDS", "Command", "Parameter"]


@dataclass(frozen=True)
class Parameter:
    """One parameter of a command, as ``encode`` takes it.

    ``minimum`` / ``maximum`` are the range ``encode`` accepts, in ``unit``: the
    document's range, or what the field's bytes hold where the document gives none;
    ``resolution`` is the step the bytes carry (a value between two steps is rounded).
    All three are None for a parameter of ``choices``. ``required``: ``encode`` raises without it
    (it has no ``default``). ``when`` names the parameter and value it belongs to, e.g.
    ``("axis", "yaw")`` for ``yaw_deg``; None when it always belongs.

    >>> from analyzer import COMMANDS
    >>> control = next(c for c in COMMANDS if c.name == "gimbal_control")
    >>> speed = control.parameters[0]
    >>> speed.name, speed.unit, speed.minimum, speed.maximum, speed.resolution, speed.default
    ('pan_speed_dps', 'deg/s', -100.0, 100.0, 0.01, 0)
    """

    name: str
    unit: str
    minimum: float | None
    maximum: float | None
    resolution: float | None
    choices: tuple[str, ...]
    default: float | str | None
    required: bool
    when: tuple[str, str] | None
    description: str
    note: str = ""  # a limit of some models only (the 35x zoom), a value the document fixes

    @classmethod
    def of(cls, field: Field, when: tuple[str, str] | None = None) -> Parameter:
        """The public view of one field of the command table."""
        minimum = maximum = resolution = None
        choices: tuple[str, ...] = ()
        if field.labels is not None:
            choices = tuple(field.labels.values())
            if field.other_label is not None:
                choices += (field.other_label,)
        else:
            lo, hi = field.encodable_limits()
            minimum, maximum = float(field.scale(lo)), float(field.scale(hi))
            resolution = float(field.scale(1))
        return cls(
            name=field.name,
            unit=field.unit,
            minimum=minimum,
            maximum=maximum,
            resolution=resolution,
            choices=choices,
            default=field.default,
            required=field.default is None,
            when=when,
            description=field.description,
            note=_note(field),
        )


def _note(field: Field) -> str:
    if field.expected is not None:
        unit = f" {field.unit}" if field.unit else ""
        return f"the document prescribes {field.scale(field.expected)}{unit}"
    return field.soft_note


@dataclass(frozen=True)
class Command:
    """One command of chapter 2.1: what ``encode`` takes and what decoding names it.

    >>> from analyzer import COMMANDS
    >>> angle = next(c for c in COMMANDS if c.name == "specified_angle")
    >>> angle.component, hex(angle.s_id), hex(angle.cmd), angle.title
    ('gimbal', '0xf', '0x8', 'Specified Angle')
    >>> [(p.name, p.when) for p in angle.parameters]
    ... # doctest: +NORMALIZE_WHITESPACE
    [('axis', None), ('yaw_deg', ('axis', 'yaw')), ('pitch_deg', ('axis', 'pitch')),
     ('zoom', ('axis', 'zoom')), ('coordinate_system', None)]
    """

    name: str
    component: str  # "gimbal" (S_ID 0x0F) or "dual_sensor" (S_ID 0x1F)
    s_id: int
    cmd: int
    title: str  # the document's name for it
    description: str
    parameters: tuple[Parameter, ...]

    @classmethod
    def of(cls, row: command_table.CommandRow) -> Command:
        """The public view of one row of the command table."""
        parameters: list[Parameter] = []
        selector = row.selector
        if selector is not None:
            parameters.append(Parameter.of(selector))
            labels = selector.labels or {}
            for raw, variant in row.variants.items():
                when = (selector.name, labels.get(raw, str(raw)))
                parameters += [Parameter.of(field, when) for field in variant]
        parameters += [Parameter.of(field) for field in row.params]
        return cls(
            name=row.name,
            component=COMPONENT_NAMES[row.s_id],
            s_id=row.s_id,
            cmd=row.cmd,
            title=row.title,
            description=row.description,
            parameters=tuple(parameters),
        )


COMMANDS: tuple[Command, ...] = tuple(Command.of(row) for row in command_table.COMMANDS)
"""Every command of the protocol document, each a ``Command`` with its ``Parameter``s in
physical units and the ranges ``encode`` accepts: the gimbal's (S_ID 0x0F) first, then the
dual-sensor camera's (S_ID 0x1F). Made from the one command table that decoding and
``encode`` use, so it names exactly what they know (the module's example lists the
dual-sensor camera's)."""
