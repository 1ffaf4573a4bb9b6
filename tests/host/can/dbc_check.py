#!/usr/bin/python3
"""Checks the generated DBC file with an independent implementation (python3-canmatrix):
every single-frame message of the catalogue is in it with the right length, CAN FD flag and
signals, and frames our codecs encoded (protocol_samples) decode to the same raw values.

  dbc_check.py KINCAL_DBC SAMPLES_FILE
"""
import sys

import canmatrix
import canmatrix.formats


def main(dbc_path, samples_path):
    db = canmatrix.formats.loadp_flat(dbc_path)
    failures = 0
    checked = 0
    for line in open(samples_path, encoding="ascii"):
        fields = line.split()
        can_id, data, raws = int(fields[0], 16), bytes.fromhex(fields[1]), [int(v) for v in fields[2:]]
        frame = db.frame_by_id(canmatrix.ArbitrationId(can_id))
        if frame is None:
            print(f"dbc_check: 0x{can_id:03X} missing from {dbc_path}")
            return 1
        if frame.size != len(data):
            print(f"dbc_check: {frame.name}: DBC length {frame.size}, frame length {len(data)}")
            return 1
        if frame.is_fd != (len(data) > 8):
            print(f"dbc_check: {frame.name}: CAN FD flag {frame.is_fd} for a {len(data)}-byte frame")
            return 1
        decoded = frame.decode(data)
        names = [s.name for s in sorted(frame.signals, key=lambda s: s.start_bit)]
        if len(names) != len(raws):
            print(f"dbc_check: {frame.name}: {len(names)} signals in the DBC, {len(raws)} in the catalogue")
            return 1
        for name, raw in zip(names, raws):
            got = decoded[name].raw_value
            if got != raw:
                failures += 1
                if failures <= 5:
                    print(f"dbc_check: {frame.name}.{name}: canmatrix decodes {got}, our codec wrote {raw}")
        checked += 1
    print(f"dbc_check: {checked} frames of {len(db.frames)} messages decoded by canmatrix, {failures} mismatches")
    return 1 if failures or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
