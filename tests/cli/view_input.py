#!/usr/bin/env python3
"""Drive a running `tetpack view` like a user, through the X server's XTEST extension (libXtst, by
ctypes): wait for its first screenshot (the view runs with --keys P), drag with the left button
(orbit), the middle button (pan) and the right button (zoom), turn the wheel, then press W (scene), P
(screenshot) and Q. Usage: view_input.py SCREENSHOT SCENE (both written by the view)."""
import ctypes
import os
import sys
import time

x11 = ctypes.CDLL("libX11.so.6")
xtst = ctypes.CDLL("libXtst.so.6")
x11.XOpenDisplay.restype = ctypes.c_void_p
x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
x11.XStringToKeysym.restype = ctypes.c_ulong
x11.XKeysymToKeycode.argtypes = [ctypes.c_void_p, ctypes.c_ulong]
x11.XFlush.argtypes = [ctypes.c_void_p]
for f in (xtst.XTestFakeMotionEvent, xtst.XTestFakeButtonEvent, xtst.XTestFakeKeyEvent):
    f.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int, ctypes.c_ulong] + \
        ([ctypes.c_ulong] if f is xtst.XTestFakeMotionEvent else [])
display = x11.XOpenDisplay(None)
if not display:
    sys.exit("view_input: cannot open the display")


def wait_for(path, what, seconds=120):
    end = time.time() + seconds
    while not os.path.exists(path):
        if time.time() > end:
            sys.exit("view_input: no %s after %d s" % (what, seconds))
        time.sleep(0.05)


def move(x, y):
    xtst.XTestFakeMotionEvent(display, -1, x, y, 0)
    x11.XFlush(display)
    time.sleep(0.05)


def button(b, down):
    xtst.XTestFakeButtonEvent(display, b, 1 if down else 0, 0)
    x11.XFlush(display)
    time.sleep(0.05)


def drag(b, x0, y0, x1, y1):
    move(x0, y0)
    button(b, True)
    for i in range(1, 5):
        move(x0 + (x1 - x0) * i // 4, y0 + (y1 - y0) * i // 4)
    button(b, False)


def key(name):
    code = x11.XKeysymToKeycode(display, x11.XStringToKeysym(name.encode()))
    xtst.XTestFakeKeyEvent(display, code, 1, 0)
    xtst.XTestFakeKeyEvent(display, code, 0, 0)
    x11.XFlush(display)
    time.sleep(0.05)


shot, scene = sys.argv[1], sys.argv[2]
wait_for(shot, "first frame")
os.remove(shot)
drag(1, 20, 20, 50, 30)   # orbit
drag(2, 30, 30, 36, 26)   # pan
drag(3, 30, 30, 30, 40)   # zoom out
button(4, True)           # the wheel, one step toward the screen: zoom in
button(4, False)
key("w")
key("p")
wait_for(scene, "scene after W")
wait_for(shot, "screenshot after P")
key("q")
