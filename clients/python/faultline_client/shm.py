"""Shared-memory frames (docs/protocol.md §16): the pixels as numpy arrays mapped from the publisher's ring, no copy.

An injector with `output_shm: true` writes each raw frame once into a slot of a ring file under /dev/shm and sends
[topic][CameraFrame] with CameraFrame.shm saying where it is. The slot is reused `slot_count` frames later and the
publisher never waits, so every slot carries a sequence word (seqlock: odd while written, then 2 x position + 2):
a frame whose slot no longer holds the descriptor's sequence was overwritten, before it was read (counted in
`overwritten_before_read`) or while it was in use (`intact()` returns False and counts `overwritten_during_use`).
Reading the sequence word and then the pixels relies on loads staying in order, as they do on x86-64 (TSO).
"""
import mmap
import os
import struct
from typing import Dict, Optional

import numpy as np

_MAGIC = 0x474E524D4853464C  # "FLSHMRNG"
_VERSION = 1
# magic, version, slot_count, slot_bytes, stride, data_offset, ring_id, writer_pid, frames_written, slot_header_bytes
_HEADER = struct.Struct("<QIIQQQQQQQ")


class ShmRing:
    """One mapped ring file (read-only)."""

    def __init__(self, path: str):
        fd = os.open(path, os.O_RDONLY)
        try:
            self._mm = mmap.mmap(fd, 0, prot=mmap.PROT_READ)
        finally:
            os.close(fd)
        (magic, version, self.slot_count, self.slot_bytes, self.stride, data_offset, self.ring_id, _, _,
         slot_header) = _HEADER.unpack_from(self._mm, 0)
        if magic != _MAGIC:
            raise ValueError(f"{path}: not a Faultline shm ring (bad magic)")
        if version != _VERSION:
            raise ValueError(f"{path}: shm ring version {version}, expected {_VERSION}")
        if data_offset + self.stride * self.slot_count > len(self._mm):
            raise ValueError(f"{path}: file shorter than its header says")
        self.path = path
        self.data_offset = data_offset
        self.slot_header = slot_header
        self.bytes = np.frombuffer(self._mm, np.uint8)  # the whole file, read-only, no copy
        # The slots' sequence words: one uint64 at the start of each slot.
        self.sequences = np.ndarray((self.slot_count,), dtype="<u8", buffer=self._mm, offset=data_offset,
                                    strides=(self.stride,))

    def sequence(self, slot: int) -> int:
        return int(self.sequences[slot])


class ShmReader:
    """Maps each publisher's ring on first use (again when the publisher restarted with a new ring_id)."""

    def __init__(self):
        self.rings: Dict[str, ShmRing] = {}
        self.overwritten_before_read = 0
        self.overwritten_during_use = 0

    def _ring(self, shm) -> ShmRing:
        ring = self.rings.get(shm.path)
        if ring is None or ring.ring_id != shm.ring_id:
            ring = ShmRing(shm.path)
            if ring.ring_id != shm.ring_id:
                raise LookupError(f"{shm.path}: ring {ring.ring_id} is not the descriptor's {shm.ring_id}")
            self.rings[shm.path] = ring
        return ring

    def pixels(self, header) -> Optional[np.ndarray]:
        """The frame's payload_bytes bytes as a flat uint8 view into the ring, or None (counted) when the slot was
        overwritten before it was read. ValueError for a descriptor that does not fit the ring."""
        shm = header.shm
        try:
            ring = self._ring(shm)
        except (OSError, LookupError):  # the publisher exited or restarted since: that frame is gone
            self.overwritten_before_read += 1
            return None
        expected = ring.data_offset + ring.stride * shm.slot + ring.slot_header
        if (shm.slot >= ring.slot_count or shm.offset != expected or header.payload_bytes > ring.slot_bytes
                or shm.sequence == 0 or shm.sequence % 2):
            raise ValueError(f"shm descriptor does not fit {shm.path}: slot {shm.slot} offset {shm.offset}")
        if ring.sequence(shm.slot) != shm.sequence:
            self.overwritten_before_read += 1
            return None
        return ring.bytes[shm.offset:shm.offset + header.payload_bytes]

    def intact(self, header) -> bool:
        """True while the slot still holds this frame; call after using the pixels (False is counted)."""
        ring = self.rings.get(header.shm.path)
        if ring is not None and ring.ring_id == header.shm.ring_id and \
                ring.sequence(header.shm.slot) == header.shm.sequence:
            return True
        self.overwritten_during_use += 1
        return False

    @property
    def overwritten(self) -> int:
        return self.overwritten_before_read + self.overwritten_during_use
