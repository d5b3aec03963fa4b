"""Protocol-buffer wire-format primitives, for writing messages without message objects.

Written from the protobuf encoding specification
(https://protobuf.dev/programming-guides/encoding/): a field is a *key*
``(field_number << 3) | wire_type`` followed by its value; wire type 0 is a base-128 varint
(least significant group first, high bit = "more bytes follow"; a negative int32 is
sign-extended to 64 bits, so 10 bytes), 1 a little-endian 64-bit value, 2 a varint byte
length followed by that many bytes. A packed repeated scalar field is one wire-type-2 record
holding the values back to back; a repeated string field is one wire-type-2 record per
string. Proto3 leaves out scalar fields equal to zero and empty repeated fields.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np

VARINT = 0
FIXED64 = 1
LEN = 2

F8 = np.dtype("<f8")
"""Protobuf ``double``: IEEE 754 binary64, little-endian (non-finite values kept bit for bit)."""

_ONE_BYTE = [bytes((i,)) for i in range(0x80)]
_INT32_MIN, _INT32_MAX = -(2**31), 2**31 - 1


def varint(value: int) -> bytes:
    """Base-128 varint of an unsigned 64-bit value, or of a negative int32/int64 as protobuf
    writes it: sign-extended to 64 bits, hence always 10 bytes.

    Raises:
        ValueError: ``value`` does not fit in 64 bits.
    """
    if value < 0x80:
        if value >= 0:
            return _ONE_BYTE[value]
        value = int(value)
        if value < -(2**63):
            raise ValueError(f"varint out of range: {value}")
        value += 1 << 64
    elif value < 0x4000:
        return bytes((value & 0x7F | 0x80, value >> 7))
    else:
        value = int(value)
        if value >> 64:
            raise ValueError(f"varint out of range: {value}")
    out = bytearray()
    while value > 0x7F:
        out.append(value & 0x7F | 0x80)
        value >>= 7
    out.append(value)
    return bytes(out)


def key(field_number: int, wire_type: int) -> bytes:
    """The encoded key of a field."""
    return varint(field_number << 3 | wire_type)


def length_delimited(field_key: bytes, payload: bytes) -> bytes:
    """One wire-type-2 record: key, varint byte length, payload."""
    return field_key + varint(len(payload)) + payload


def packed_int32(field_key: bytes, values: Any) -> bytes:
    """A packed repeated ``int32`` field (``b""`` when empty, as proto3 omits it).

    Raises:
        ValueError: a value is outside the int32 range (protobuf refuses those too).
    """
    arr = np.asarray(values)
    if arr.size == 0:
        return b""
    arr = arr.astype(np.int64, copy=False).ravel()
    low, high = int(arr.min()), int(arr.max())
    if low >= 0 and high < 0x80:  # the usual case: lane indices 0..127, one byte each
        return length_delimited(field_key, arr.astype(np.uint8).tobytes())
    if low < _INT32_MIN or high > _INT32_MAX:
        raise ValueError(f"int32 field value out of range: {low if low < 0 else high}")
    memo: dict[int, bytes] = {}
    payload = b"".join([memo.get(v) or memo.setdefault(v, varint(v)) for v in arr.tolist()])
    return length_delimited(field_key, payload)


def packed_bool(field_key: bytes, values: Any) -> bytes:
    """A packed repeated ``bool`` field: one byte (0 or 1) per value; ``b""`` when empty."""
    arr = np.asarray(values, dtype=np.bool_).ravel()
    if arr.size == 0:
        return b""
    return length_delimited(field_key, arr.view(np.uint8).tobytes())


def string_record(field_key: bytes, value: str) -> bytes:
    """One element of a repeated ``string`` field (UTF-8)."""
    return length_delimited(field_key, value.encode("utf-8"))


def repeated_string(field_key: bytes, values: Iterable[str]) -> bytes:
    """A whole repeated ``string`` field (empty strings included, as protobuf writes them)."""
    return b"".join([string_record(field_key, v) for v in values])


class StringColumn:
    """Encodes one repeated ``string`` field step after step, reusing what repeats.

    The list passed last time is remembered with its encoding: the same list object, or a
    list with the same values, costs one comparison. Otherwise each string's record comes
    from a per-string cache (edge names and vehicle ids repeat across steps), which is
    cleared when it holds ``max_cached`` strings so an open network with endless new ids
    cannot grow it without bound.

    Columns are treated as read-only: a list changed in place and passed again compares
    equal to itself and keeps its old encoding.

    Args:
        field_key: the encoded key of the field.
        max_cached: per-string cache size at which it is cleared.
    """

    def __init__(self, field_key: bytes, max_cached: int = 65_536) -> None:
        self.field_key = field_key
        self.max_cached = max_cached
        self._last: Sequence[str] = []
        self._block = b""
        self._cache: dict[str, bytes] = {}

    def encode(self, values: Sequence[str]) -> bytes:
        """The encoded field for ``values``."""
        if values is self._last:
            return self._block
        if not isinstance(values, list):
            values = list(values)  # e.g. a numpy array, whose == compares element-wise
        if values == self._last:  # a new list with the same values
            self._last = values
            return self._block
        cache = self._cache
        try:
            block = b"".join(map(cache.__getitem__, values))
        except KeyError:
            if len(cache) >= self.max_cached:
                cache.clear()
            for v in values:
                if v not in cache:
                    cache[v] = string_record(self.field_key, v)
            block = b"".join(map(cache.__getitem__, values))
        self._last, self._block = values, block
        return block


class ArrayColumn:
    """Encodes one packed numeric field step after step, reusing the last encoding.

    The same array object, or an array with the same dtype, shape and bytes, reuses the
    previous encoding (lane indices and RL flags rarely change).

    Args:
        encode: builds the encoded field from an array.
    """

    def __init__(self, encode: Callable[[Any], bytes]) -> None:
        self._encode = encode
        self._last: Any = None
        self._raw = b""
        self._dtype: np.dtype[Any] | None = None
        self._shape: tuple[int, ...] = ()
        self._block = b""

    def encode(self, values: Any) -> bytes:
        """The encoded field for ``values``."""
        if values is self._last:
            return self._block
        arr = np.asarray(values)
        raw, dtype = arr.tobytes(), arr.dtype
        # (dtype.str would be a clearer key, but it costs 4x the rest of this check)
        if (
            raw != self._raw
            or arr.shape != self._shape
            or not (dtype is self._dtype or dtype == self._dtype)
        ):
            self._block = self._encode(arr)
            self._raw, self._dtype, self._shape = raw, dtype, arr.shape
        self._last = values
        return self._block
