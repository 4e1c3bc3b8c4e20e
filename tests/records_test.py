#!/usr/bin/env python3
"""Every dump record type is described once, in src/render/dump_records.cpp (dumpRecordTypes: what
check-dump compares and the Python module's record_dtype reads); what restates it must say the same:
scripts/read-dump.py's dtypes (for readers with NumPy only) and the record table of
docs/dump-format.md, type by type and field by field (offset, kind, name, shape, size). The OpenCL
kernels' records.cl is checked against the C++ structs by its layout kernel (lucent-opencl).

  records_test.py SOURCE_DIR     (with the lucent module on PYTHONPATH)
"""
import importlib.util
import os
import re
import sys

import lucent

root = sys.argv[1]
failures = []
spec = importlib.util.spec_from_file_location("read_dump", os.path.join(root, "scripts", "read-dump.py"))
read_dump = importlib.util.module_from_spec(spec)
spec.loader.exec_module(read_dump)

KINDS = {"f4": "float", "f2": "half", "u4": "uint32", "i4": "int32", "u2": "uint16", "u8": "uint64"}
types = lucent.record_types()

# read-dump.py's dtypes: the same types, each the dtype record_dtype gives.
if sorted(read_dump.DTYPES) != sorted(types):
    failures.append(f"read-dump.py has types {sorted(read_dump.DTYPES)}, the C++ table {sorted(types)}")
for name in types:
    if name in read_dump.DTYPES and read_dump.DTYPES[name] != lucent.record_dtype(name):
        failures.append(f"read-dump.py's {name} is {read_dump.DTYPES[name]}, the C++ table's {lucent.record_dtype(name)}")


def entries_of(dtype):
    """(offset, kind, name, dims) of each field, as the document writes them: 12: float power[3]."""
    if dtype.names is None:
        return [(0, KINDS[dtype.str[1:]], None, "")]
    out = []
    for field in dtype.names:
        sub, offset = dtype.fields[field][:2]
        base, shape = (sub.subdtype if sub.subdtype else (sub, ()))
        out.append((offset, KINDS[base.str[1:]], field, "".join(f"[{n}]" for n in shape)))
    return out


# docs/dump-format.md's record table: a row per type, with its size and its fields in order.
with open(os.path.join(root, "docs", "dump-format.md"), encoding="utf-8") as f:
    text = f.read()
table = text[text.index("| type | bytes | fields (offset: type name) |"):]
table = table[:table.index("\n\n")]
rows = {}
for line in table.splitlines()[2:]:
    m = re.match(r"\| `(\w+)` \| (\d+) \| (.*) \|$", line)
    if not m:
        failures.append(f"docs/dump-format.md: a record table row that is not | `type` | bytes | fields |: {line[:60]}")
        continue
    entries = [(int(o), kind, name or None, dims) for o, kind, name, dims in
               re.findall(r"(\d+): (float|half|uint16|uint32|int32|uint64)(?: (\w+)((?:\[\d+\])*))?", m.group(3))]
    rows[m.group(1)] = (int(m.group(2)), entries)
if sorted(rows) != sorted(types):
    failures.append(f"docs/dump-format.md's table has types {sorted(rows)}, the C++ table {sorted(types)}")
for name in types:
    if name not in rows:
        continue
    dtype = lucent.record_dtype(name)
    size, entries = rows[name]
    if size != dtype.itemsize:
        failures.append(f"docs/dump-format.md: {name} is {size} bytes, the C++ table's {dtype.itemsize}")
    if entries != entries_of(dtype):
        failures.append(f"docs/dump-format.md: {name}'s fields are {entries}, the C++ table's {entries_of(dtype)}")

for f in failures:
    print("records_test:", f)
print(f"records_test: {len(types)} record types, {len(failures)} differences")
sys.exit(1 if failures else 0)
