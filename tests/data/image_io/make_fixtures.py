#!/usr/bin/env python3
"""Writes the small image fixtures of test_image_io.cpp with an encoder of
its own (zlib + struct), independent of the libpng/libtiff code under test.
Run from this folder: python3 make_fixtures.py"""
import struct
import zlib


def chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def png(name, width, height, bit_depth, color_type, rows, extra=b"", interlace=0):
    """rows: list of raw scanline bytes (without filter byte)."""
    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, color_type, 0, 0, interlace)
    raw = b"".join(b"\x00" + r for r in rows)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + extra
    data += chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
    with open(name, "wb") as f:
        f.write(data)


def adam7_png(name, width, height, values):
    """8-bit grey, Adam7 interlaced; values[y][x]."""
    passes = [(0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2)]
    raw = b""
    for x0, y0, dx, dy in passes:
        xs = list(range(x0, width, dx))
        ys = list(range(y0, height, dy))
        if not xs or not ys:
            continue
        for y in ys:
            raw += b"\x00" + bytes(values[y][x] for x in xs)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 1)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
    data += chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
    with open(name, "wb") as f:
        f.write(data)


# 16-bit grey 3x2, samples big-endian as PNG stores them.
g16 = [[0x0102, 0xFFFE, 0x0000], [0x0001, 0x8000, 0x1234]]
png("gray16_3x2.png", 3, 2, 16, 0, [b"".join(struct.pack(">H", v) for v in r) for r in g16])
# 8-bit grey 9x7 Adam7 interlaced, value = 10*y + x.
adam7_png("gray8_adam7_9x7.png", 9, 7, [[10 * y + x for x in range(9)] for y in range(7)])
# Kinds a frame reader must refuse.
png("rgb8_2x2.png", 2, 2, 8, 2, [bytes([1, 2, 3, 4, 5, 6])] * 2)
png("gray_alpha8_2x2.png", 2, 2, 8, 4, [bytes([1, 255, 2, 255])] * 2)
png("rgba8_2x2.png", 2, 2, 8, 6, [bytes([1, 2, 3, 255, 4, 5, 6, 255])] * 2)
png("palette8_2x2.png", 2, 2, 8, 3, [bytes([0, 1])] * 2, extra=chunk(b"PLTE", bytes([0, 0, 0, 255, 255, 255])))
png("gray4_4x2.png", 4, 2, 4, 0, [bytes([0x12, 0x34])] * 2)


def tiff(name, endian, width, height, spp, bits, sample_format, pixel_bytes):
    """Baseline uncompressed single-strip TIFF."""
    e = "<" if endian == "II" else ">"
    entries = [
        (256, 4, 1, width), (257, 4, 1, height), (258, 3, 1, bits), (259, 3, 1, 1),
        (262, 3, 1, 1), (273, 4, 1, 0), (277, 3, 1, spp), (278, 4, 1, height),
        (279, 4, 1, len(pixel_bytes)), (284, 3, 1, 1), (339, 3, 1, sample_format),
    ]
    header = (b"II" if endian == "II" else b"MM") + struct.pack(e + "HI", 42, 8)
    ifd_size = 2 + 12 * len(entries) + 4
    data_offset = 8 + ifd_size
    ifd = struct.pack(e + "H", len(entries))
    for tag, typ, count, value in entries:
        if tag == 273:
            value = data_offset
        if typ == 3:
            ifd += struct.pack(e + "HHIHH", tag, typ, count, value, 0)
        else:
            ifd += struct.pack(e + "HHII", tag, typ, count, value)
    ifd += struct.pack(e + "I", 0)
    with open(name, "wb") as f:
        f.write(header + ifd + pixel_bytes)


# Big-endian float32, 2x2, 1 channel: 1.5, -2.25, a NaN with payload 0x7fc00001, +inf.
tiff("float32_be_2x2.tiff", "MM", 2, 2, 1, 32, 3,
     struct.pack(">ff", 1.5, -2.25) + struct.pack(">I", 0x7FC00001) + struct.pack(">f", float("inf")))
# uint16 grey: not float, must be refused by the float reader.
tiff("uint16_2x2.tiff", "II", 2, 2, 1, 16, 1, struct.pack("<4H", 1, 2, 3, 4))
