"""The messages between kingen and a child process that runs foreign code, as plain data.

A child that loads a plugin runs code kingen did not write, so nothing it sends may be able
to run code in kingen's own process, and nothing a plugin writes into the channel may pass
for kingen's message. Each message is one frame::

    b"KGN1" | body length (8 bytes, big-endian) | HMAC-SHA256(key, body) (32 bytes) | body
    body = JSON length (4 bytes, big-endian) | JSON (UTF-8) | the arrays' bytes, in order

The JSON is ``{"kind": text, "value": tree}``; the tree holds only null, booleans, numbers
(NaN and infinities included), text, lists and objects, and numpy arrays as
``{"$array": [dtype, shape]}`` whose bytes follow the JSON, in order. Only numeric and
boolean dtypes travel (never Python objects); a frame is at most MAX_FRAME_BYTES. The key
is drawn by the parent before it forks the child and never sent: bytes a plugin writes
into the channel fail the frame's check, so at most they make its own run fail. Decoding
gives plain data; turning it into kingen's objects, checked field by field, is the
receiver's (:func:`typed`).
"""

import dataclasses
import hashlib
import hmac
import json
import os
import secrets
import select
import struct
import time

import numpy as np

MAGIC = b"KGN1"
HEADER = struct.Struct(">4sQ32s")
LENGTH = struct.Struct(">I")
MAX_FRAME_BYTES = 256 << 20
"""The largest frame read: a recorded chunk of CEART's solutions is about 16 MB."""
DTYPES = frozenset(np.dtype(name).str for name in (
    "bool", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "float32", "float64"))
"""The array types that travel (numpy's ``dtype.str``, byte order included)."""
ARRAY = "$array"


class WireError(Exception):
    """A frame that is not kingen's message: cut short, too large, failing its check, or
    holding what the format does not allow. The text says which, in one line."""


def new_key():
    """A fresh key for one child's channel."""
    return secrets.token_bytes(32)


def encode(key, kind, value):
    """The frame of message ``kind`` (text) holding ``value``: None, bool, int, float, str,
    lists, tuples (sent as lists), dicts with text keys, dataclasses (sent as dicts of their
    fields), numpy scalars and numeric arrays. TypeError for anything else (a kingen defect)."""
    arrays = []
    text = json.dumps({"kind": kind, "value": _plain(value, arrays)}, separators=(",", ":")).encode()
    body = b"".join([LENGTH.pack(len(text)), text, *(array.tobytes() for array in arrays)])
    if len(body) > MAX_FRAME_BYTES:
        raise TypeError(f"a {kind} message of {len(body)} bytes is larger than a frame may be")
    return HEADER.pack(MAGIC, len(body), hmac.digest(key, body, hashlib.sha256)) + body


def _plain(value, arrays):
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, float)):  # numpy's float64 is a float
        return value
    if isinstance(value, np.generic) and value.dtype.str in DTYPES:
        return value.item()
    if isinstance(value, np.ndarray) and value.dtype.str in DTYPES:
        arrays.append(np.ascontiguousarray(value))
        return {ARRAY: [value.dtype.str, list(value.shape)]}
    if isinstance(value, (list, tuple)):
        return [_plain(item, arrays) for item in value]
    if isinstance(value, dict) and all(isinstance(key, str) and key != ARRAY for key in value):
        return {key: _plain(item, arrays) for key, item in value.items()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {item.name: _plain(getattr(value, item.name), arrays) for item in dataclasses.fields(value)}
    raise TypeError(f"{type(value).__name__} cannot travel between processes")


class Receiver:
    """The reading end of a channel (a file descriptor) and its key: ``receive(timeout)``
    returns each message as (kind, plain value)."""

    def __init__(self, descriptor, key):
        self._descriptor = descriptor
        self._key = key
        os.set_blocking(descriptor, False)

    def receive(self, timeout):
        """The next message as (kind, value), None when the channel was closed between
        messages, or TimeoutError when no whole message came within ``timeout`` seconds.
        WireError when what came is not kingen's message (closed within a frame included)."""
        deadline = time.monotonic() + timeout
        header = self._read(HEADER.size, deadline, between=True)
        if header is None:
            return None
        magic, length, tag = HEADER.unpack(header)
        if magic != MAGIC:
            raise WireError("bytes that are not kingen's message")
        if length > MAX_FRAME_BYTES:
            raise WireError(f"a message of {length} bytes, larger than any kingen sends")
        body = self._read(length, deadline)
        if not hmac.compare_digest(tag, hmac.digest(self._key, body, hashlib.sha256)):
            raise WireError("a message that is not kingen's (its check failed)")
        return _decode(body)

    def _read(self, count, deadline, between=False):
        """``count`` bytes; None for end of file before the first when ``between`` messages."""
        parts, got = [], 0
        while got < count:
            remaining = deadline - time.monotonic()
            if remaining <= 0 or not select.select([self._descriptor], [], [], remaining)[0]:
                raise TimeoutError
            part = os.read(self._descriptor, min(count - got, 1 << 20))
            if not part:
                if between and got == 0:
                    return None
                raise WireError("a message cut short")
            parts.append(part)
            got += len(part)
        return b"".join(parts)

    def fileno(self):
        """The reading end's descriptor (for select)."""
        return self._descriptor

    def close(self):
        os.close(self._descriptor)


def _decode(body):
    """(kind, value) of a checked frame's body (see the module's docstring)."""
    try:
        (size,) = LENGTH.unpack_from(body)
        message = json.loads(body[LENGTH.size:LENGTH.size + size].decode())
        kind, tree = message["kind"], message["value"]
    except (struct.error, ValueError, TypeError, KeyError, RecursionError) as error:
        raise WireError(f"a message kingen cannot read ({type(error).__name__})") from None
    if not isinstance(kind, str) or set(message) != {"kind", "value"}:
        raise WireError("a message kingen cannot read (its kind)")
    offset = [LENGTH.size + size]
    value = _rebuilt(tree, body, offset)
    if offset[0] != len(body):
        raise WireError("a message with bytes beyond its arrays")
    return kind, value


def _rebuilt(tree, body, offset):
    if isinstance(tree, list):
        return [_rebuilt(item, body, offset) for item in tree]
    if not isinstance(tree, dict):
        return tree
    if ARRAY not in tree:
        return {key: _rebuilt(item, body, offset) for key, item in tree.items()}
    try:
        (dtype, shape), = tree.values()
        valid = dtype in DTYPES and all(type(extent) is int and extent >= 0 for extent in shape)
    except (TypeError, ValueError):
        valid = False
    if not valid:
        raise WireError("a message with an array kingen cannot read")
    count = np.dtype(dtype).itemsize * int(np.prod(shape, dtype=object))
    if offset[0] + count > len(body):
        raise WireError("a message whose arrays are cut short")
    array = np.frombuffer(body, dtype=dtype, count=count // np.dtype(dtype).itemsize, offset=offset[0])
    offset[0] += count
    return array.reshape(shape).copy()


class Sender:
    """The writing end of a channel (a file descriptor) and its key."""

    def __init__(self, descriptor, key):
        self._descriptor = descriptor
        self._key = key

    def send(self, kind, value):
        frame = memoryview(encode(self._key, kind, value))
        while frame:
            frame = frame[os.write(self._descriptor, frame):]

    def close(self):
        os.close(self._descriptor)


def typed(kind, value):
    """``value`` (plain data) as an instance of ``kind`` (a dataclass, or a type pydantic
    knows), checked field by field; WireError naming the first field that does not fit."""
    from pydantic import TypeAdapter, ValidationError

    try:
        return _adapter(TypeAdapter, kind).validate_python(value)
    except ValidationError as error:
        first = error.errors()[0]
        where = ".".join(str(part) for part in first["loc"]) or "the message"
        raise WireError(f"a {getattr(kind, '__name__', 'message')} kingen cannot read ({where}: {first['msg']})") \
            from None


_ADAPTERS = {}


def _adapter(make, kind):
    if kind not in _ADAPTERS:
        _ADAPTERS[kind] = make(kind)
    return _ADAPTERS[kind]
