"""The JSON form of a reproduce run's typed records: one converter over their fields, and their base class.

Every record is a keyword-only dataclass (:func:`record`): a field that is
missing or misspelt raises TypeError where the object is built, and
ValueError naming the file and the key where it is read back.  The JSON form
is derived from the fields by one converter (:func:`to_json`,
:meth:`JsonRecord.from_json_dict`), by these rules:

- the keys are the field names, in declaration order;
- a field whose default is None is absent while it is None, not null
  (a None in a required field, or in a dictionary, is written as null);
- a field declared with :data:`WRITTEN_FLAT` metadata is written as its record's (or
  dictionary's) keys among its owner's, not as a nested object;
- a field declared with :data:`NOT_WRITTEN` is not written (and read back if
  present), one with :data:`ABSENT_AT_DEFAULT` is absent at its default;
- dictionary keys typed ``int`` are written as strings; numbers and strings
  are written as they are, for :func:`json.dumps` to format.

Why a converter of our own rather than a library: :ref:`contributing-decisions`.
"""

from __future__ import annotations

import functools
import types
import typing
from dataclasses import MISSING, dataclass, fields, is_dataclass
from typing import Any, NamedTuple

#: The decorator of every record: a dataclass with slots and keyword-only fields.
record = functools.partial(dataclass, slots=True, kw_only=True)

_HOW = "results_json"  # the key of a field's metadata that says how it is written
#: ``field(metadata=...)`` of a field written as its record's (or dictionary's) keys among its owner's,
WRITTEN_FLAT = {_HOW: "flat"}
#: of a field that the JSON form does not hold,
NOT_WRITTEN = {_HOW: "not written"}
#: of a field whose key is absent while it has its default.
ABSENT_AT_DEFAULT = {_HOW: "absent at default"}


class _Field(NamedTuple):
    name: str
    how: str | None
    default: Any
    required: bool
    holds_records: bool  # else its value is written as it is
    record: type | None  # the record class of a (possibly optional) record type
    read: Any  # _reader of its type


def _optional_of(hint):
    """X for ``X | None``, else None."""
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        args = [arg for arg in typing.get_args(hint) if arg is not type(None)]
        return args[0] if len(args) == 1 else None
    return None


def _holds_records(hint):
    return is_dataclass(hint) or any(_holds_records(arg) for arg in typing.get_args(hint))


@functools.cache
def _plan(cls):
    """The fields of a record class, in declaration order, with what the converter needs to know of them."""
    hints = typing.get_type_hints(cls)
    return tuple(
        _Field(
            name=f.name,
            how=f.metadata.get(_HOW),
            default=f.default,
            required=f.default is MISSING and f.default_factory is MISSING,
            holds_records=_holds_records(hints[f.name]),
            record=next((h for h in (_optional_of(hints[f.name]), hints[f.name]) if is_dataclass(h)), None),
            read=_reader(hints[f.name]),
        )
        for f in fields(cls)
    )


@functools.cache
def _own_keys(cls):
    """The keys of a record's JSON object that its fields (flattened records' included) claim."""
    keys = []
    for f in _plan(cls):
        if f.how != "flat":
            keys.append(f.name)
        elif f.record is not None:
            keys.extend(_own_keys(f.record))
    return frozenset(keys)


def to_json(value):
    """The JSON form of a record, or of a dictionary or list of them, for :func:`json.dumps`."""
    if is_dataclass(value):
        return _recordto_json(value)
    if isinstance(value, dict):
        return {str(key) if isinstance(key, int) else key: to_json(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [to_json(item) for item in value]
    return value


def _recordto_json(record):
    document = {}
    for f in _plan(type(record)):
        value = getattr(record, f.name)
        if (
            f.how == "not written"
            or (value is None and f.default is None)
            or (f.how == "absent at default" and value == f.default)
        ):
            continue
        value = to_json(value) if f.holds_records else value
        if f.how == "flat":
            document.update(value)
        else:
            document[f.name] = value
    return document


def _from_json(hint, document, source):
    """Read :func:`to_json`'s form of type ``hint`` back; ValueError naming ``source`` and the key if it is bad."""
    try:
        return _reader(hint)(document)
    except _BadDocument as error:
        path, problem = error.args
        raise ValueError(f"{source}: {'.'.join(map(str, path)) or 'the document'} {problem}") from None


class _BadDocument(Exception):
    """([keys from the document's top to the bad value], what is wrong with it)."""

    def within(self, key):
        self.args[0].insert(0, key)
        return self


def _expect(value, kinds, what):
    if not isinstance(value, kinds) or (isinstance(value, bool) and bool not in kinds):
        raise _BadDocument([], f"should be {what}, not {type(value).__name__} {value!r:.40}")


_SCALARS = {
    float: ((int, float), "a number"),
    int: ((int,), "an integer"),
    str: ((str,), "a string"),
    bool: ((bool,), "true or false"),
}


def _as_is(value):
    return value


@functools.cache
def _reader(hint):
    """The function that checks a parsed JSON value of type ``hint`` and returns it as that type."""
    inner = _optional_of(hint)
    if inner is not None:
        read = _reader(inner)
        return lambda value: None if value is None else read(value)
    if is_dataclass(hint):
        return functools.partial(_read_record, hint)
    origin, args = typing.get_origin(hint) or hint, typing.get_args(hint)
    if origin is dict:
        key_type, item_type = args or (str, Any)
        return functools.partial(_read_dict, _read_int_key if key_type is int else _as_is, _reader(item_type))
    if origin is list:
        return functools.partial(_read_list, _reader(args[0] if args else Any))
    if hint in _SCALARS:
        return functools.partial(_read_scalar, *_SCALARS[hint])
    return _as_is


def _read_scalar(kinds, what, value):
    _expect(value, kinds, what)
    return value


def _read_int_key(key):
    if not key.lstrip("-").isdigit():
        raise _BadDocument([], f"has the key {key!r}, which is not an integer")
    return int(key)


def _read_dict(read_key, read_item, document):
    _expect(document, (dict,), "an object")
    if read_key is read_item is _as_is:
        return document
    read = {}
    for key, item in document.items():
        read_as = read_key(key)
        try:
            read[read_as] = read_item(item)
        except _BadDocument as error:
            raise error.within(key) from None
    return read


def _read_list(read_item, document):
    _expect(document, (list,), "a list")
    if read_item is _as_is or (
        getattr(read_item, "func", None) is _read_scalar and {type(item) for item in document} <= set(read_item.args[0])
    ):
        return document  # the common case, checked at once
    read = []
    for index, item in enumerate(document):
        try:
            read.append(read_item(item))
        except _BadDocument as error:
            raise error.within(index) from None
    return read


def _read_record(cls, document):
    _expect(document, (dict,), f"an object ({cls.__name__})")
    own, plan = _own_keys(cls), _plan(cls)
    unknown = [key for key in document if key not in own]
    collects_the_rest = any(f.how == "flat" and f.record is None for f in plan)
    if unknown and not collects_the_rest:
        raise _BadDocument([], f"has the key {unknown[0]!r}, which {cls.__name__} does not know")
    values = {}
    for f in plan:
        if f.how == "flat" and f.record is not None:
            part = {key: document[key] for key in _own_keys(f.record) if key in document}
            if part or f.required:
                values[f.name] = _read_record(f.record, part)
        elif f.how == "flat":
            values[f.name] = f.read({key: document[key] for key in unknown})
        elif f.name in document:
            try:
                values[f.name] = f.read(document[f.name])
            except _BadDocument as error:
                raise error.within(f.name) from None
        elif f.required:
            raise _BadDocument([], f"lacks the key {f.name!r} ({cls.__name__})")
    return cls(**values)


class JsonRecord:
    """``to_json_dict`` and ``from_json_dict`` of every record, by the module's rules."""

    __slots__ = ()

    def to_json_dict(self):
        """The record's JSON form, a dict (see the module's rules)."""
        return to_json(self)

    @classmethod
    def from_json_dict(cls, document, *, source="results.json"):
        """The record of ``document`` (parsed JSON) read from ``source``; ValueError naming it and a bad key."""
        record = _from_json(cls, document, source)
        cls._check_read(document, source)
        return record

    @classmethod
    def _check_read(cls, document, source):
        """Raise ValueError naming ``source`` if a read document breaks a rule its types do not say."""
