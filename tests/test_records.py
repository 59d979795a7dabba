"""transpiler.records: quick_init records behave as the frozen dataclasses they are (fields, defaults, equality,
frozenness, replace, pickling), slotted or not; a builder makes the same records as the class call."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import pytest

from transpiler.ir import Op, Operand
from transpiler.diagnostics import Span
from transpiler.records import builder, quick_init, replaced


@quick_init
@dataclasses.dataclass(frozen=True, slots=True)
class _Slotted:
    name: str
    count: int = 2
    tags: tuple[str, ...] = ()


@quick_init
@dataclasses.dataclass(frozen=True)
class _WithDict:
    name: str
    count: int = 2


@pytest.mark.parametrize("cls", [_Slotted, _WithDict])
def test_quick_init_fills_fields_and_defaults(cls):
    record = cls("a")
    assert (record.name, record.count) == ("a", 2)
    assert type(record) is cls
    assert cls("a", count=5) == cls(name="a", count=5) != record
    assert hash(cls("a")) == hash(record)


@pytest.mark.parametrize("cls", [_Slotted, _WithDict])
def test_quick_init_record_stays_frozen(cls):
    record = cls("a")
    with pytest.raises(dataclasses.FrozenInstanceError):
        record.name = "b"
    assert record.name == "a"


def test_slotted_record_has_no_instance_dict():
    assert not hasattr(_Slotted("a"), "__dict__")


@pytest.mark.parametrize("record", [_Slotted("a", 3, ("x",)), _WithDict("a", 3),
                                    Op("LD", "L", Span("f.src", 4, 1), Operand("M", 12), ("note",), chain_open=True)])
def test_copies_replace_and_pickle_give_equal_records(record):
    assert pickle.loads(pickle.dumps(record)) == record
    assert copy.deepcopy(record) == record and copy.copy(record) == record
    field = dataclasses.fields(record)[0].name
    assert dataclasses.replace(record) == record
    assert replaced(record, **{field: "z"}) == dataclasses.replace(record, **{field: "z"})


def test_quick_init_refuses_what_it_cannot_build():
    @dataclasses.dataclass
    class Mutable:
        name: str

    with pytest.raises(TypeError):
        quick_init(Mutable)


def test_quick_init_refuses_a_slotted_layout_it_cannot_switch():
    # The class switch of a slotted record needs the plain slots of the record alone: a slotted base or a weak
    # reference slot change the layout, and the first record built would fail. Refused when decorated instead.
    @dataclasses.dataclass(frozen=True, slots=True)
    class Base:
        name: str

    @dataclasses.dataclass(frozen=True, slots=True)
    class Derived(Base):
        count: int = 0

    @dataclasses.dataclass(frozen=True, slots=True, weakref_slot=True)
    class Weak:
        name: str

    for cls in (Derived, Weak):
        with pytest.raises(TypeError, match="quick_init takes a slotted record only"):
            quick_init(cls)


@quick_init
@dataclasses.dataclass(frozen=True, slots=True)
class _Checked:
    low: int
    high: int = 10

    def __post_init__(self):
        if self.low > self.high:
            raise ValueError("low above high")


def test_builder_makes_the_records_of_the_class_call():
    build = builder(_Slotted)
    for args, kwargs in [(("a",), {}), (("a", 5), {}), (("a",), {"tags": ("x",)}), ((), {"name": "b", "count": 0})]:
        record = build(*args, **kwargs)
        assert type(record) is _Slotted and record == _Slotted(*args, **kwargs)
        assert repr(record) == repr(_Slotted(*args, **kwargs))
    with pytest.raises(dataclasses.FrozenInstanceError):
        build("a").name = "b"
    with pytest.raises(TypeError):
        build()                         # the class's own signature: a required field stays required
    assert builder(_Checked)(3).high == 10
    with pytest.raises(ValueError):     # __post_init__ runs as under the class call
        builder(_Checked)(11)


def test_builder_takes_slotted_quick_init_records_only():
    @dataclasses.dataclass(frozen=True, slots=True)
    class Plain:
        name: str

    for cls in (_WithDict, Plain):
        with pytest.raises(TypeError):
            builder(cls)


@quick_init
@dataclasses.dataclass(frozen=True, slots=True)
class _Single:
    name: str


def test_replaced_changes_the_named_fields_only():
    record = _Slotted("a", 3, ("x",))
    assert replaced(record, count=4) == _Slotted("a", 4, ("x",))
    assert replaced(record, tags=(), name="b") == _Slotted("b", 3, ())
    assert replaced(record) == record and replaced(_Single("a"), name="b") == _Single("b")
    assert replaced(_WithDict("a"), count=0) == _WithDict("a", 0)
    with pytest.raises(TypeError):
        replaced(record, colour="red")
