"""Frozen records that are quick to build: a faster `__init__` for the frozen dataclasses made once per source line.

A frozen dataclass stores each field through `object.__setattr__` (its own `__setattr__` refuses), which makes an
Op of fourteen fields cost about 2 us to build: on a 100 000-line project the front end builds several such
records per line (span, instruction, operand, op) and spent a quarter of its time in their constructors.
`quick_init` gives such a class an `__init__` that stores the fields the way `object.__setattr__` ends up doing
(through the slot descriptors, or into the instance dict), with the same signature and defaults. The class stays
frozen: assigning a field afterwards still raises FrozenInstanceError; equality, hashing, ordering, repr and
`dataclasses.replace` are the dataclass's own. A `__post_init__` is called after the fields are stored, as the
dataclass's own `__init__` calls it.

`builder` goes one step further for the loops that build a record per source line: a plain function with the
class's parameters that builds the same record as the class call, at about half its cost.
"""

from __future__ import annotations

import dataclasses
import operator
from typing import Callable, TypeVar

T = TypeVar("T")


def quick_init(cls: type[T]) -> type[T]:
    """Replace the generated `__init__` of the frozen dataclass `cls` (plain defaults only, no init-only fields)."""
    if not dataclasses.is_dataclass(cls) or not cls.__dataclass_params__.frozen:
        raise TypeError(f"{cls.__name__} is not a frozen dataclass")
    fields = dataclasses.fields(cls)
    params, namespace = _parameters(cls, fields)
    slotted = "__slots__" in cls.__dict__
    if slotted:
        # The record is filled in as an instance of a plain class with the same slots (whose fields take an ordinary,
        # fast attribute store), then given back its own class: CPython allows that switch only between classes of
        # the same layout, so the record may have no base with slots of its own and no weak-reference slot (checked
        # here, where a mistake shows at import and not at the first record built); nothing else can see the record
        # in between.
        namespace["_fields_only"] = _fields_only_class(cls)
        namespace["_set_class"] = object.__setattr__
        stores = (["    record_class = type(self)", "    _set_class(self, '__class__', _fields_only)"]
                  + [f"    self.{f.name} = {f.name}" for f in fields] + ["    self.__class__ = record_class"])
    else:
        # (one store per field into the instance dict: faster than building keyword arguments for dict.update)
        stores = ["    _stored = self.__dict__"] + [f"    _stored[{f.name!r}] = {f.name}" for f in fields]
    if hasattr(cls, "__post_init__"):
        stores.append("    self.__post_init__()")
    init = _compiled("__init__", ["self"] + params, stores, namespace)
    cls._quick_fields = tuple(f.name for f in fields)
    cls._quick_values = _field_reader(cls._quick_fields)          # (for replaced)
    cls._quick_position = {name: i for i, name in enumerate(cls._quick_fields)}
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    init.__doc__ = cls.__init__.__doc__
    cls.__init__ = init
    return cls


def builder(cls: type[T]) -> Callable[..., T]:
    """A function that builds a record of the slotted `quick_init` class `cls`: the parameters and the record of
    `cls(...)`. In CPython 3.11 a class call goes through `type.__call__` to `__init__` (with keyword arguments
    through a generic call that packs them into a dict): about twice the cost of a plain function that makes the
    record as a fields-only instance, fills it in and gives it its class (as `quick_init`'s `__init__` does)."""
    if "_quick_fields" not in cls.__dict__ or "__slots__" not in cls.__dict__:
        raise TypeError(f"{cls.__name__} is not a slotted quick_init record")
    fields = dataclasses.fields(cls)
    params, namespace = _parameters(cls, fields)
    namespace.update(_new=object.__new__, _fields_only=_fields_only_class(cls), _record_class=cls)
    body = (["    record = _new(_fields_only)"] + [f"    record.{f.name} = {f.name}" for f in fields]
            + ["    record.__class__ = _record_class"]
            + (["    record.__post_init__()"] if hasattr(cls, "__post_init__") else []) + ["    return record"])
    build = _compiled(f"new_{cls.__name__}", params, body, namespace)
    build.__doc__ = f"{cls.__name__}(...) built by a plain function call (records.builder)."
    return build


def _parameters(cls: type, fields: tuple[dataclasses.Field, ...]) -> tuple[list[str], dict[str, object]]:
    """The parameter list of the record's constructor and a namespace holding the defaults it names."""
    params: list[str] = []
    namespace: dict[str, object] = {}
    for f in fields:
        if not f.init or f.default_factory is not dataclasses.MISSING:
            raise TypeError(f"{cls.__name__}.{f.name}: only fields with plain defaults are supported")
        if f.default is dataclasses.MISSING:
            params.append(f.name)
        else:
            namespace[f"_default_{f.name}"] = f.default
            params.append(f"{f.name}=_default_{f.name}")
    return params, namespace


def _fields_only_class(cls: type) -> type:
    """A plain class with the slots of the slotted record `cls`: the record's class may be switched from it."""
    if cls.__bases__ != (object,) or "__weakref__" in cls.__slots__:
        raise TypeError(f"{cls.__name__}: quick_init takes a slotted record only without a base class and "
                        "without weakref_slot")
    return type(f"{cls.__name__}Fields", (), {"__slots__": cls.__slots__})


def _field_reader(names: tuple[str, ...]) -> Callable[[object], tuple]:
    """A function that reads the fields `names` of a record into a tuple, in C when there are several."""
    if len(names) > 1:
        return operator.attrgetter(*names)
    return lambda record: tuple(getattr(record, name) for name in names)    # (attrgetter gives one value bare)


def _compiled(name: str, params: list[str], body: list[str], namespace: dict[str, object]) -> Callable:
    """The function `name` with these parameters and body lines, its global names looked up in `namespace`."""
    source = f"def {name}({', '.join(params)}):\n" + "\n".join(body or ["    pass"]) + "\n"
    exec(source, namespace)     # noqa: S102 - the text is built from the field names only
    return namespace[name]


def replaced(record: T, **changes: object) -> T:
    """`dataclasses.replace` for a record of a `quick_init` class: the same new record, built without looking the
    fields up again (replace costs several times the constructor; the front end and the back ends use it for
    every patched jump, call and nested block)."""
    cls = type(record)
    values = list(cls._quick_values(record))
    position = cls._quick_position
    for name, value in changes.items():
        if name not in position:
            raise TypeError(f"{cls.__name__} has no field {name}")
        values[position[name]] = value
    return cls(*values)
