#!/usr/bin/env python3
"""Writes the raw text files of a CMU Plaza run (NAME_GT.txt, NAME_DR.txt,
NAME_TD.txt, NAME_TL.txt) from the MATLAB 5 file that GTSAM ships it in
(examples/Data/Plaza2_.mat), for `rff_convert --format=plaza`.

Usage: plaza_mat_to_text.py Plaza2_.mat OUT_DIR [NAME]

Reads only what those files hold: top-level double matrices, compressed
(miCOMPRESSED) or not. Needs numpy.
"""
import os
import struct
import sys
import zlib

import numpy as np

MI_MATRIX, MI_COMPRESSED = 14, 15
NUMERIC_TYPES = {1: '<i1', 2: '<u1', 3: '<i2', 4: '<u2', 5: '<i4', 6: '<u4',
                 7: '<f4', 9: '<f8', 12: '<i8', 13: '<u8'}


def elements(buf, offset, end):
    """(type, bytes) of the data elements in buf[offset:end]."""
    while offset < end:
        tag = struct.unpack_from('<I', buf, offset)[0]
        if tag >> 16:  # Small element: type and size share one word.
            kind, size = tag & 0xffff, tag >> 16
            yield kind, buf[offset + 4:offset + 4 + size]
            offset += 8
            continue
        kind, size = struct.unpack_from('<II', buf, offset)
        yield kind, buf[offset + 8:offset + 8 + size]
        # Compressed elements are not padded to 8 bytes; the rest are.
        offset += 8 + size + (0 if kind == MI_COMPRESSED else -size % 8)


def numeric_matrix(data):
    """(name, array) of a miMATRIX element; None for other classes."""
    parts = list(elements(data, 0, len(data)))
    class_id = parts[0][1][0]
    if class_id in (1, 2, 3, 4, 5):  # cell, struct, object, char, sparse
        return None
    dims = np.frombuffer(parts[1][1], dtype='<i4')
    name = parts[2][1].decode()
    kind, raw = parts[3]
    values = np.frombuffer(raw, dtype=NUMERIC_TYPES[kind]).astype(float)
    return name, values.reshape(tuple(dims[::-1])).T  # Column-major.


def load(path):
    try:
        buf = open(path, 'rb').read()
    except OSError as e:
        sys.exit(f'{path}: cannot read: {e.strerror}')
    if not buf.startswith(b'MATLAB 5.0 MAT-file'):
        sys.exit(f'{path}: not a MATLAB 5 MAT-file')
    variables = {}
    try:
        for kind, data in elements(buf, 128, len(buf)):
            if kind == MI_COMPRESSED:
                data = zlib.decompress(data)
                kind, data = next(elements(data, 0, len(data)))
            if kind == MI_MATRIX:
                matrix = numeric_matrix(data)
                if matrix is not None:
                    variables[matrix[0]] = matrix[1]
    except (zlib.error, struct.error, ValueError, KeyError, IndexError,
            StopIteration) as e:
        sys.exit(f'{path}: truncated or corrupt MAT-file ({e})')
    return variables


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    path, out_dir = sys.argv[1], sys.argv[2]
    name = sys.argv[3] if len(sys.argv) == 4 else \
        os.path.basename(path).split('_')[0].split('.')[0]
    variables = load(path)
    missing = [k for k in ('GT', 'DR', 'TD', 'TL') if k not in variables]
    if missing:
        sys.exit(f'{path}: no {", ".join(missing)} matrix')
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as e:
        sys.exit(f'{out_dir}: cannot create the output directory: '
                 f'{e.strerror}')
    for key in ('GT', 'DR', 'TD', 'TL'):
        out = os.path.join(out_dir, f'{name}_{key}.txt')
        np.savetxt(out, variables[key], fmt='%.10g')
        print(f'wrote {out}: {variables[key].shape[0]} rows')


if __name__ == '__main__':
    main()
