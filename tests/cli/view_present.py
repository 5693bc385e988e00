#!/usr/bin/env python3
"""Check what a running `tetpack view` shows, from the X server's side (libX11 and libXtst, by ctypes):
the window's pixels (XGetImage) against the view's own screenshot, its title, and a resize. The view runs
with --keys P --screenshot SHOT. Steps: wait for SHOT; the title must match TITLE_RE; grab the window into
OUT_DIR/grab-WxH.png until it equals SHOT (PSNR >= 40 dB); resize the window to WxH (the second size),
press P, wait for the new SHOT of that size, grab again and compare; press Q.
Usage: view_present.py SHOT OUT_DIR TITLE_RE WxH"""
import ctypes
import os
import re
import struct
import sys
import time
import zlib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from png_read import pixels as read_png  # noqa: E402

x11 = ctypes.CDLL("libX11.so.6")
xtst = ctypes.CDLL("libXtst.so.6")
VP, UL = ctypes.c_void_p, ctypes.c_ulong


class XImage(ctypes.Structure):  # the head of Xlib's XImage, up to the colour masks
    _fields_ = [("width", ctypes.c_int), ("height", ctypes.c_int), ("xoffset", ctypes.c_int),
                ("format", ctypes.c_int), ("data", VP), ("byte_order", ctypes.c_int),
                ("bitmap_unit", ctypes.c_int), ("bitmap_bit_order", ctypes.c_int), ("bitmap_pad", ctypes.c_int),
                ("depth", ctypes.c_int), ("bytes_per_line", ctypes.c_int), ("bits_per_pixel", ctypes.c_int),
                ("red_mask", UL), ("green_mask", UL), ("blue_mask", UL)]


x11.XOpenDisplay.restype = VP
x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
x11.XDefaultRootWindow.restype = UL
x11.XDefaultRootWindow.argtypes = [VP]
x11.XQueryTree.argtypes = [VP, UL, ctypes.POINTER(UL), ctypes.POINTER(UL), ctypes.POINTER(ctypes.POINTER(UL)),
                           ctypes.POINTER(ctypes.c_uint)]
x11.XFetchName.argtypes = [VP, UL, ctypes.POINTER(ctypes.c_char_p)]
x11.XGetImage.restype = ctypes.POINTER(XImage)
x11.XGetImage.argtypes = [VP, UL, ctypes.c_int, ctypes.c_int, ctypes.c_uint, ctypes.c_uint, UL, ctypes.c_int]
x11.XGetGeometry.argtypes = [VP, UL, ctypes.POINTER(UL)] + [ctypes.POINTER(ctypes.c_int)] * 2 + \
    [ctypes.POINTER(ctypes.c_uint)] * 4
x11.XResizeWindow.argtypes = [VP, UL, ctypes.c_uint, ctypes.c_uint]
x11.XStringToKeysym.restype = UL
x11.XKeysymToKeycode.argtypes = [VP, UL]
x11.XFlush.argtypes = [VP]
x11.XSync.argtypes = [VP, ctypes.c_int]
x11.XFree.argtypes = [VP]
xtst.XTestFakeKeyEvent.argtypes = [VP, ctypes.c_uint, ctypes.c_int, UL]
display = x11.XOpenDisplay(None)
if not display:
    sys.exit("view_present: cannot open the display")


def fail(message):
    key("q")
    sys.exit("view_present: " + message)


def wait_for(path, what, seconds=120):
    end = time.time() + seconds
    while not os.path.exists(path):
        if time.time() > end:
            fail("no %s after %d s" % (what, seconds))
        time.sleep(0.05)
    time.sleep(0.2)  # written by the view: let it finish


def key(name):
    code = x11.XKeysymToKeycode(display, x11.XStringToKeysym(name.encode()))
    xtst.XTestFakeKeyEvent(display, code, 1, 0)
    xtst.XTestFakeKeyEvent(display, code, 0, 0)
    x11.XFlush(display)
    time.sleep(0.05)


def view_window():
    """The top-level window whose name is a tetpack view's title (path: field ... | device | fps ...)."""
    root, parent, children, n = UL(), UL(), ctypes.POINTER(UL)(), ctypes.c_uint()
    x11.XQueryTree(display, x11.XDefaultRootWindow(display), ctypes.byref(root), ctypes.byref(parent),
                   ctypes.byref(children), ctypes.byref(n))
    found = None
    for i in range(n.value):
        name = ctypes.c_char_p()
        if x11.XFetchName(display, children[i], ctypes.byref(name)) and name.value:
            if b" fps, " in name.value:
                found = (children[i], name.value.decode())
            x11.XFree(name)
    if n.value:
        x11.XFree(children)
    return found


def grab(window):
    """The window's pixels as an (h, w, 4) uint8 array, alpha 255."""
    root, x, y = UL(), ctypes.c_int(), ctypes.c_int()
    w, h, border, depth = ctypes.c_uint(), ctypes.c_uint(), ctypes.c_uint(), ctypes.c_uint()
    x11.XGetGeometry(display, window, ctypes.byref(root), ctypes.byref(x), ctypes.byref(y), ctypes.byref(w),
                     ctypes.byref(h), ctypes.byref(border), ctypes.byref(depth))
    image = x11.XGetImage(display, window, 0, 0, w.value, h.value, ~0 & 0xffffffffffffffff, 2).contents  # ZPixmap
    assert image.bits_per_pixel == 32 and image.byte_order == 0, "expected a 24-bit screen, 32 bits per pixel LSB"
    raw = np.frombuffer(ctypes.string_at(image.data, image.bytes_per_line * image.height), dtype=np.uint32)
    raw = raw.reshape(image.height, image.bytes_per_line // 4)[:, :image.width]
    out = np.empty((image.height, image.width, 4), dtype=np.uint8)
    for c, mask in enumerate((image.red_mask, image.green_mask, image.blue_mask)):
        shift = (mask & -mask).bit_length() - 1
        out[:, :, c] = (raw >> shift) & 0xff
    out[:, :, 3] = 255
    return out


def write_png(path, rgba):
    h, w = rgba.shape[:2]
    rows = b"".join(b"\0" + rgba[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def psnr(a, b):
    if a.shape != b.shape:
        return -1.0
    d = (a[:, :, :3].astype(np.float64) - b[:, :, :3].astype(np.float64))
    mse = float(np.mean(d * d))
    return float("inf") if mse == 0 else 10 * np.log10(255.0 * 255.0 / mse)


def grab_until_equal(window, shot, out_dir):
    """Grab until the window shows the screenshot (a present may land a moment after the file)."""
    want = read_png(shot)
    end, best = time.time() + 20, -1.0
    while True:
        got = grab(window)
        best = psnr(got, want)
        if best >= 40 or time.time() > end:
            break
        time.sleep(0.1)
    path = os.path.join(out_dir, "grab-%dx%d.png" % (got.shape[1], got.shape[0]))
    write_png(path, got)
    print("window %dx%d against the screenshot %dx%d: psnr %.2f (%s)" %
          (got.shape[1], got.shape[0], want.shape[1], want.shape[0], best, path))
    if best < 40:
        fail("the window does not show the screenshot (%s)" % path)


shot, out_dir, title_re, size = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
wait_for(shot, "first frame")
found = view_window()
if not found:
    fail("no window titled as tetpack view's")
window, title = found
print("title: " + title)
if not re.search(title_re, title):
    fail("the title does not match %r" % title_re)
grab_until_equal(window, shot, out_dir)
width, height = (int(v) for v in size.split("x"))
os.remove(shot)
x11.XResizeWindow(display, window, width, height)
x11.XSync(display, 0)
time.sleep(0.3)
key("p")
wait_for(shot, "screenshot after the resize")
got = read_png(shot)
if got.shape[:2] != (height, width):
    fail("the screenshot after the resize is %dx%d, not %s" % (got.shape[1], got.shape[0], size))
grab_until_equal(window, shot, out_dir)
title = view_window()[1]
print("title after the resize: " + title)
if not title.endswith(", %s" % size):
    fail("the title after the resize does not end with the new size")
key("q")
