"""MAVLink FTP (PX4's ``mavlink_ftp``): not modelled by the built-in vehicle, and said so.

PX4 v1.15 serves files over FILE_TRANSFER_PROTOCOL; clients use it for logs, parameters
(MAVProxy asks for ``@PARAM/param.pck`` first) and component metadata. The built-in vehicle has
no file system to serve: every request is answered at once with a NAK ``UnknownCommand`` (the
protocol's way to say an opcode is not supported), so a client falls back to the plain MAVLink
protocols without waiting for its timeout, and the first request gets a STATUSTEXT naming what is
missing.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["ERR_UNKNOWN_COMMAND", "PAYLOAD_LEN", "RSP_NAK", "nak"]

PAYLOAD_LEN = 251  # FILE_TRANSFER_PROTOCOL.payload
RSP_NAK = 129  # kRspNak
ERR_UNKNOWN_COMMAND = 7  # MAV_FTP_ERR_UNKNOWNCOMMAND


def nak(request: Sequence[int], error: int = ERR_UNKNOWN_COMMAND) -> list[int]:
    """The NAK payload answering ``request`` (a FILE_TRANSFER_PROTOCOL payload): the next sequence
    number, the request's session, opcode NAK, size 1, the request's opcode, the error in data[0]
    (PayloadHeader: seq_number u16, session u8, opcode u8, size u8, req_opcode u8,
    burst_complete u8, padding u8, offset u32, data)."""
    req = list(request) + [0] * (PAYLOAD_LEN - len(request))
    seq = (req[0] | req[1] << 8) + 1 & 0xFFFF
    out = [0] * PAYLOAD_LEN
    out[0], out[1] = seq & 0xFF, seq >> 8
    out[2] = req[2]
    out[3] = RSP_NAK
    out[4] = 1
    out[5] = req[3]
    out[12] = error
    return out
