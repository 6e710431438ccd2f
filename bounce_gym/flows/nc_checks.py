"""What a NetCDF flow file may declare, checked from its header before any array is read.

A file of a few hundred bytes can declare a field of 10^9 values (a dimension's length is a
number in the header; HDF5 stores unwritten chunks as nothing) or chunks of 10^9 values that a
read of one value decompresses whole; a truncated classic (NetCDF-3) file reads back zeros
where its end is missing, without an error. So before the loader reads an array:

* the values it will read are capped: ``u`` (and ``v``, ``land``, which are no larger) may
  declare at most `max_values` values — cells x layers x times — and no read variable may have
  a chunk of more values or more than `MAX_CHUNKS` chunks (`check_variable`, run by
  `bounce_gym.flows.netcdf.flow_from_dataset` on the variables it reads). The cap is
  `DEFAULT_MAX_VALUES` (5·10^7: loading takes about 40 bytes a value at its peak, so about
  2 GB), or the environment variable `MAX_VALUES_VARIABLE`, or ``max_values=`` per call;
* what opening the file reads is bounded (`check_header`): every attribute at most
  `MAX_ATTRIBUTE_VALUES` values or characters, and every coordinate variable xarray loads as
  an index on open within the same limits as the variables read;
* a classic file's header is parsed here first (`check_classic`), skipping names and values:
  its counts must fit in the file (the NetCDF library would try to honour a count of 2^31
  dimensions in a 14-byte file) and the file must be as long as its data reach.

* a file may not declare far more values than it holds bytes (`check_expansion`): NetCDF-4
  compresses, and a file of 400 KB of compressed constants declaring 5·10^7 values loads into
  1.7 GB. Under the default cap, ``u`` may declare at most `MAX_VALUES_PER_BYTE` (4) values per
  byte of the file — 16 times the 0.25 of uncompressed float32, more than real ocean fields
  compress — or `EXPANSION_FLOOR` (2^22) values whatever the file's size; ``max_values=`` or
  `MAX_VALUES_VARIABLE`, given, accepts what it says instead.

Each refusal is a `FlowFileError` whose one line names the file, the variable or attribute and
what is allowed.
"""

from __future__ import annotations

import math
import os
import struct
from pathlib import Path

from bounce_gym.errors import ConfigError, FlowFileError
from bounce_gym.validate import integer

__all__ = ["DEFAULT_MAX_VALUES", "EXPANSION_FLOOR", "MAX_ATTRIBUTE_VALUES", "MAX_CHUNKS",
           "MAX_VALUES_PER_BYTE", "MAX_VALUES_VARIABLE", "check_classic", "check_expansion",
           "check_header", "check_variable", "classic_data_end", "max_values"]

#: Values (cells x layers x times) a flow file may declare, unless changed.
DEFAULT_MAX_VALUES = 50_000_000
#: The environment variable that changes `DEFAULT_MAX_VALUES` (a positive integer).
MAX_VALUES_VARIABLE = "BOUNCE_GYM_MAX_FLOW_VALUES"
#: Values (or characters) of one attribute.
MAX_ATTRIBUTE_VALUES = 1 << 20
#: Chunks of one variable that is read (each costs a lookup and a read of its own).
MAX_CHUNKS = 1_000_000
#: Values ``u`` may declare per byte of the file under the default cap (`check_expansion`).
MAX_VALUES_PER_BYTE = 4
#: Values ``u`` may declare under the default cap whatever the file's size (about 160 MiB to
#: load).
EXPANSION_FLOOR = 1 << 22
#: Bytes loading takes per declared value of ``u`` at its peak (measured: 38).
BYTES_PER_VALUE = 40


def max_values(value: object = None) -> int:
    """The cap on declared values: ``value`` if given, else ``$BOUNCE_GYM_MAX_FLOW_VALUES`` if
    set, else `DEFAULT_MAX_VALUES`."""
    if value is not None:
        return integer("max_values", value, 1)
    text = os.environ.get(MAX_VALUES_VARIABLE)
    if text is None:
        return DEFAULT_MAX_VALUES
    try:
        return integer(MAX_VALUES_VARIABLE, int(text.strip()), 1)
    except ValueError:
        raise ConfigError(f"{MAX_VALUES_VARIABLE}: expected a positive integer, got "
                          f"{text!r}") from None


def explicit_cap(value: object = None) -> bool:
    """Whether the cap was given (``max_values=``, or `MAX_VALUES_VARIABLE` set): then it
    alone bounds what a file may declare, and `check_expansion` does not apply."""
    return value is not None or os.environ.get(MAX_VALUES_VARIABLE) is not None


def check_expansion(source: str, label: str, sizes: dict, file_bytes: int) -> None:
    """Refuse ``u`` (``label``; ``sizes``: dimension name -> length) declaring more than
    `MAX_VALUES_PER_BYTE` values per byte of a file of ``file_bytes`` bytes, and more than
    `EXPANSION_FLOOR` values: a small compressed file that would load into gigabytes."""
    total = math.prod(sizes.values())
    allowed = max(EXPANSION_FLOOR, MAX_VALUES_PER_BYTE * file_bytes)
    if total > allowed:
        raise FlowFileError(
            f"{source}: {label}: declares {total:,} values in a file of {file_bytes:,} bytes "
            f"({total / max(file_bytes, 1):,.0f} per byte, about "
            f"{BYTES_PER_VALUE * total / 2**20:,.0f} MiB to load); a file may declare at most "
            f"{MAX_VALUES_PER_BYTE} per byte (or {EXPANSION_FLOOR:,} in all) unless max_values=..."
            f" or ${MAX_VALUES_VARIABLE} accepts more")


def check_variable(source: str, label: str, sizes: dict, chunks, cap: int) -> None:
    """Refuse a variable to be read (``label``, e.g. ``u ('uo')``) that declares more than
    ``cap`` values or has a dimension longer than ``cap`` (``sizes``: name -> length), chunks
    (``chunks``: lengths, or None when not chunked) of more than ``cap`` values, or more than
    `MAX_CHUNKS` chunks."""
    total = math.prod(sizes.values())
    shape = " x ".join(f"{name} {size}" for name, size in sizes.items())
    if total > cap or max(sizes.values(), default=0) > cap:
        raise FlowFileError(f"{source}: {label}: declares {total:,} values ({shape}); at most "
                            f"{cap:,} are read (max_values=..., or ${MAX_VALUES_VARIABLE})")
    if not chunks or len(chunks) != len(sizes):  # none, or stale after a selection
        return
    chunk = math.prod(int(c) for c in chunks)
    count = math.prod(-(-size // int(c)) for size, c in zip(sizes.values(), chunks, strict=True))
    if chunk > cap or count > MAX_CHUNKS:
        raise FlowFileError(f"{source}: {label}: chunks of {tuple(int(c) for c in chunks)} "
                            f"({chunk:,} values, {count:,} chunks for {shape}); allowed are "
                            f"chunks of at most {cap:,} values and at most {MAX_CHUNKS:,} chunks")


def check_header(nc, path: Path, cap: int) -> None:
    """Check what opening the file with xarray reads: every attribute, and every coordinate
    variable (a 1-D variable named as its dimension, loaded as an index). ``nc`` is the file
    open with ``netCDF4.Dataset`` (which reads only the header); ``path`` its path."""
    _check_attributes(nc, path, "global attribute")
    for name, var in nc.variables.items():
        _check_attributes(var, path, f"attribute of {name!r}:")
        if var.dimensions == (name,):
            chunks = var.chunking()
            check_variable(str(path), f"coordinate {name!r}", {name: len(var)},
                           None if chunks == "contiguous" else chunks, cap)


def check_classic(path: Path) -> None:
    """For a classic (NetCDF-3) file, checked before the NetCDF library parses it: a header
    that holds together (no count larger than the bytes left, which the library would try to
    honour) and a file as long as the data its header declares."""
    with open(path, "rb") as f:
        if f.read(4) not in _CLASSIC_MAGIC:
            return
    end, size = classic_data_end(path), path.stat().st_size
    if size < end:
        raise FlowFileError(f"{path}: truncated NetCDF file: its header puts data up to byte "
                            f"{end:,}, the file has {size:,} bytes")


def _check_attributes(owner, path: Path, what: str) -> None:
    for name in owner.ncattrs():
        value = owner.getncattr(name)
        count = len(value) if isinstance(value, str | bytes) else getattr(value, "size", 1)
        if count > MAX_ATTRIBUTE_VALUES:
            raise FlowFileError(f"{path}: {what} {name!r} has {count:,} values; at most "
                                f"{MAX_ATTRIBUTE_VALUES:,} are read")


# -- classic (NetCDF-3) headers: where the data end ---------------------------------------------
#: the first bytes of the classic formats: CDF-1 (classic), CDF-2 (64-bit offsets), CDF-5
_CLASSIC_MAGIC = (b"CDF\x01", b"CDF\x02", b"CDF\x05")
#: bytes per value of the classic types (NC_BYTE ... NC_UINT64)
_TYPE_SIZES = {1: 1, 2: 1, 3: 2, 4: 4, 5: 4, 6: 8, 7: 1, 8: 2, 9: 4, 10: 8, 11: 8}
#: ``numrecs`` of a file still being written (CDF-1/2, CDF-5): count the records from its size
_STREAMING = ((1 << 32) - 1, (1 << 64) - 1)


def classic_data_end(path: Path) -> int:
    """The length a classic file needs for the data its header declares: the end of the last
    fixed-size variable or of the last variable's slice of the last record. Reads the header
    only, skipping names and attribute values; raises `FlowFileError` for a header that ends
    early or counts more items than it could hold."""
    with open(path, "rb") as f:
        reader = _Header(f, path.stat().st_size, str(path))
        version = reader.read(4)[3]
        wide = version == 5  # CDF-5: 64-bit counts and lengths
        offsets = version != 1  # CDF-2 and CDF-5: 64-bit data offsets
        count = reader.uint64 if wide else reader.uint32
        numrecs = count()
        dims = []
        for _ in reader.items(10, count):
            reader.skip_name(count)
            dims.append(count())
        reader.skip_attributes(count)
        records, ends = [], [0]
        for _ in reader.items(11, count):
            reader.skip_name(count)
            dimids = [count() for _ in range(reader.bounded(count(), 4))]
            reader.skip_attributes(count)
            size = _TYPE_SIZES.get(reader.uint32())
            count()  # vsize (it saturates for large variables: recomputed below)
            begin = reader.uint64() if offsets else reader.uint32()
            if size is None or any(d >= len(dims) for d in dimids):
                raise FlowFileError(f"{path}: corrupt NetCDF header (a variable's type or "
                                    "dimension is unknown)")
            record = bool(dimids) and dims[dimids[0]] == 0
            length = size * math.prod(dims[d] for d in dimids[record:])
            if record:
                records.append((begin, length))
            else:
                ends.append(begin + length)
    if records and numrecs != 0 and numrecs not in _STREAMING:
        # a record holds each record variable's slice, padded to 4 bytes unless it is the only one
        stride = records[0][1] if len(records) == 1 else sum(-(-n // 4) * 4 for _, n in records)
        ends += [begin + (numrecs - 1) * stride + length for begin, length in records]
    return max(ends)


class _Header:
    """Big-endian reads of a classic header that never read past the file or allocate more
    than the file holds."""

    def __init__(self, f, size: int, source: str) -> None:
        self.f, self.size, self.source = f, size, source

    def read(self, n: int) -> bytes:
        if n > self.size - self.f.tell():
            raise FlowFileError(f"{self.source}: truncated NetCDF header")
        return self.f.read(n)

    def uint32(self) -> int:
        return struct.unpack(">I", self.read(4))[0]

    def uint64(self) -> int:
        return struct.unpack(">Q", self.read(8))[0]

    def bounded(self, n: int, item_bytes: int) -> int:
        """``n`` items, if that many of at least ``item_bytes`` bytes fit in the rest."""
        if n * item_bytes > self.size - self.f.tell():
            raise FlowFileError(f"{self.source}: corrupt NetCDF header (it counts {n:,} items "
                                "in fewer bytes)")
        return n

    def items(self, tag: int, count) -> range:
        """The items of a list with ``tag`` (or an absent list: a zero tag)."""
        found, n = self.uint32(), count()
        if found not in (0, tag) or (found == 0 and n):
            raise FlowFileError(f"{self.source}: corrupt NetCDF header (list tag {found})")
        return range(self.bounded(n, 4))

    def skip(self, n: int) -> None:
        if n > self.size - self.f.tell():
            raise FlowFileError(f"{self.source}: truncated NetCDF header")
        self.f.seek(n, os.SEEK_CUR)

    def skip_name(self, count) -> None:
        self.skip(-(-count() // 4) * 4)

    def skip_attributes(self, count) -> None:
        for _ in self.items(12, count):
            self.skip_name(count)
            size = _TYPE_SIZES.get(self.uint32())
            if size is None:
                raise FlowFileError(f"{self.source}: corrupt NetCDF header (an attribute's type "
                                    "is unknown)")
            self.skip(-(-count() * size // 4) * 4)
