#!/usr/bin/env python3
"""Writes the seed corpus of output_file_fuzzer (input format in fuzz/output_file_property.h).

Run from the repository root: python3 fuzz/make_output_file_seeds.py
Raw-mode seeds cover a new file, a replaced file, a symbolic link, a run abandoned part way and the file
size limit below and above stdio's buffer; trace-mode seeds cover finite numbers at the edges of double
(subnormal, ±0, 1.8e308), NaN/±Inf, a size limit and an abandoned trace.
"""
import os
import struct

OUT = 'fuzz/corpus/output_file_fuzzer'


def raw(flags, old, fail_at, chunks):
    b = bytes([flags, len(old)]) + old + struct.pack('<H', fail_at)
    for piece, repeat in chunks:
        b += bytes([len(piece), repeat]) + piece
    return b


def trace(flags, old, fail_at, rho, rows):
    b = bytes([flags | 16, len(old)]) + old + struct.pack('<H', fail_at) + bytes([rho - 1])
    for row in rows:
        b += b''.join(struct.pack('<d', v) for v in row)
    return b


SEEDS = {
    'new-file-one-chunk': raw(0, b'', 0, [(b't,y\n1,2\n', 0)]),
    'replace-existing-many-chunks': raw(1, b'old,content\n1,2\n', 0,
                                        [(b'a,b\n', 3), (b'0.5,7\n', 200), (b'', 0), (b'9,9\n', 255)]),
    'symlink-replace': raw(3, b'kept\n', 0, [(b'through the link\n', 10)]),
    'abandon-midway-existing': raw(1 | 4, b'precious data\n', 300, [(b'x' * 40, 5), (b'y' * 40, 5), (b'z' * 40, 5)]),
    'abandon-new-file': raw(4, b'', 0, [(b'partial\n', 1)]),
    'size-limit-beyond-buffer': raw(1 | 8, b'old\n', 5000, [(b'0123456789abcdef', 255), (b'more', 255)]),
    'size-limit-fits': raw(8, b'', 4000, [(b'small\n', 3)]),
    'size-limit-zero-through-link': raw(1 | 2 | 8, b'linked old\n', 0, [(b'q', 0)]),
    'trace-finite': trace(0, b'', 0, 2, [
        [1.0, 0.99999999999899991, 0.17425661999999154, -0.019241651631791389, 4.9406564584124654e-324,
         7.2146262500067949e-13],
        [2.0, 1e-300, -1e300, 0.1, -0.0, 1.7976931348623157e308]]),
    'trace-nonfinite': trace(1, b'old trace\n', 0, 1, [[float('nan'), float('inf'), -float('inf'), 3.0, 2.5]]),
    'trace-size-limit': trace(1 | 8, b'old\n', 100, 3, [[1.0 * i, 0.5, 0.25, 1 / 3, 2 / 3, 1e-5, 1e5] for i in range(20)]),
    'trace-abandon': trace(1 | 4, b'old\n', 3, 1, [[1.0 * i, 0.5, 0.25, 1 / 3, 2 / 3] for i in range(8)]),
}

if __name__ == '__main__':
    os.makedirs(OUT, exist_ok=True)
    for name, data in SEEDS.items():
        with open(os.path.join(OUT, name), 'wb') as f:
            f.write(data)
