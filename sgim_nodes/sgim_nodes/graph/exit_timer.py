"""End this process with an exit code of our choice at a deadline, from a thread of the C
library: no Python runs on the way, so it fires even when another thread holds the GIL in C
code (an rclpy or DDS call that hangs), where no Python timer could run
(supervise.hard_deadline)."""

from __future__ import annotations

import ctypes
import ctypes.util
from collections.abc import Callable


def exit_later(seconds: float, code: int) -> Callable[[], None]:
    """End the process with `code` after `seconds` from a thread the C library starts
    (POSIX timer_create, SIGEV_THREAD, calling _exit): no Python runs on the way. Returns
    what disarms it."""
    class SigVal(ctypes.Union):
        _fields_ = [("sival_int", ctypes.c_int), ("sival_ptr", ctypes.c_void_p)]

    class SigEvent(ctypes.Structure):  # glibc's struct sigevent, 64 bytes on 64-bit Linux
        _fields_ = [("sigev_value", SigVal), ("sigev_signo", ctypes.c_int),
                    ("sigev_notify", ctypes.c_int), ("function", ctypes.c_void_p),
                    ("attributes", ctypes.c_void_p), ("_pad", ctypes.c_byte * 32)]

    class TimeSpec(ctypes.Structure):
        _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]

    libc = ctypes.CDLL(None, use_errno=True)
    if not hasattr(libc, "timer_create"):  # in librt before glibc 2.34
        libc = ctypes.CDLL(ctypes.util.find_library("rt"), use_errno=True)
    event = SigEvent(sigev_value=SigVal(sival_int=code), sigev_notify=2,  # SIGEV_THREAD
                     function=ctypes.cast(libc._exit, ctypes.c_void_p))
    timer = ctypes.c_void_p()
    if libc.timer_create(1, ctypes.byref(event), ctypes.byref(timer)) != 0:  # CLOCK_MONOTONIC
        raise OSError(ctypes.get_errno(), "timer_create failed")
    whole = int(seconds)
    setting = (TimeSpec * 2)(TimeSpec(0, 0), TimeSpec(whole, int((seconds - whole) * 1e9)))
    libc.timer_settime(timer, 0, setting, None)

    def disarm() -> None:
        libc.timer_delete(timer)

    return disarm
