#!/usr/bin/env python3
"""Frames and manifest for edgeplane_compare_backends, from the evaluation data (../shared/data).

    python3 benchmarks/compare_manifest.py ../shared/data OUT_DIR [EXAMPLES_DATA_DIR]

writes OUT_DIR/<set>_<image>.pgm (16-bit binary PGM, the PNG's values unchanged) and
OUT_DIR/manifest.txt with the runs of benchmarks/RESULTS.md's CUDA section: the 12 synthetic
kinect2 scenes under presets kinect2, thesis_full and thesis_half; the 8 kinect1 scenes under
kinect1, kinect360 and thesis_full; the 10 ABW images under both ABW calibrations (preset abw);
and, when EXAMPLES_DATA_DIR (examples/data) is given, the three bundled real frames under
thesis_full.  Standard library only (the PNG decoder below reads the 16-bit greyscale PNGs these
sets use), so it also runs where no image library is installed.
"""
import json
import os
import struct
import sys
import zlib


def read_png16(path):
    """(width, height, big-endian 16-bit sample bytes) of a non-interlaced 16-bit greyscale PNG."""
    data = open(path, 'rb').read()
    if data[:8] != b'\x89PNG\r\n\x1a\n':
        raise ValueError(f'{path}: not a PNG')
    pos, idat, w = 8, [], None
    while pos < len(data):
        length, kind = struct.unpack('>I4s', data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b'IHDR':
            w, h, depth, colour, _, _, interlace = struct.unpack('>IIBBBBB', body)
            if depth != 16 or colour != 0 or interlace != 0:
                raise ValueError(f'{path}: want 16-bit greyscale, non-interlaced')
        elif kind == b'IDAT':
            idat.append(body)
        pos += 12 + length
    raw = zlib.decompress(b''.join(idat))
    bpp, stride = 2, 2 * w
    out = bytearray(stride * h)
    prev = bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if f == 1:
            for i in range(bpp, stride):
                line[i] = (line[i] + line[i - bpp]) & 255
        elif f == 2:
            for i in range(stride):
                line[i] = (line[i] + prev[i]) & 255
        elif f == 3:
            for i in range(stride):
                left = line[i - bpp] if i >= bpp else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 255
        elif f == 4:
            for i in range(stride):
                a = line[i - bpp] if i >= bpp else 0
                b = prev[i]
                c = prev[i - bpp] if i >= bpp else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        elif f != 0:
            raise ValueError(f'{path}: bad filter {f}')
        out[y * stride:(y + 1) * stride] = line
        prev = line
    return w, h, bytes(out)


def write_pgm(png, pgm):
    w, h, samples = read_png16(png)
    with open(pgm, 'wb') as f:
        f.write(b'P5\n%d %d\n65535\n' % (w, h))
        f.write(samples)


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    data, out = sys.argv[1], sys.argv[2]
    examples = sys.argv[3] if len(sys.argv) > 3 else None
    os.makedirs(out, exist_ok=True)
    lines = []

    def frame(png, name):
        pgm = name + '.pgm'
        if not os.path.exists(os.path.join(out, pgm)):
            write_pgm(png, os.path.join(out, pgm))
        return pgm

    for cam, presets in (('kinect2', ['kinect2', 'thesis_full', 'thesis_half']),
                         ('kinect1', ['kinect1', 'kinect360', 'thesis_full'])):
        folder = os.path.join(data, 'synthetic-dev', cam)
        for js in sorted(f for f in os.listdir(folder) if f.startswith('scene_') and f.endswith('.json')):
            s = json.load(open(os.path.join(folder, js)))
            c = s['camera']
            pgm = frame(os.path.join(folder, js[:-5] + '_depth.png'), f"{cam}_{s['scene']}")
            for p in presets:
                lines.append(f"{cam}_{s['scene']}_{p} {pgm} {c['fx']} {c['fy']} {c['cx']} {c['cy']} "
                             f"{s['depth_scale_m_per_unit']} {p}")
    abw = json.load(open(os.path.join(data, 'abw-dev', 'intrinsics.json')))
    cals = list(abw['calibrations'].values())
    for img in abw['per_image_calibration']:
        pgm = frame(os.path.join(data, 'abw-dev', 'depth', img + '.png'), 'abw_' + img)
        for k, c in enumerate(cals):
            lines.append(f"abw_{img}_cal{k} {pgm} {c['fx']} {c['fy']} {c['cx']} {c['cy']} 0.0001 abw")
    if examples:
        for name, png, k, scale in (
                ('tum', 'tum_fr3_long_office.png', '535.4 539.2 320.1 247.6', '0.0002'),
                ('icl', 'icl_living_room.png', '481.2 -480.0 319.5 239.5', '0.0002'),
                ('cape', 'cape_depth_0.png', '575.9268544880447 576.4079160109325 315.1502635638817 '
                 '230.58580662101753', '0.001')):
            lines.append(f"{name} {frame(os.path.join(examples, png), name)} {k} {scale} thesis_full")
    with open(os.path.join(out, 'manifest.txt'), 'w') as f:
        f.write('\n'.join(lines) + '\n')
    print(f'{len(lines)} runs in {os.path.join(out, "manifest.txt")}')


if __name__ == '__main__':
    main()
