#!/usr/bin/env python3
"""Boots the STM32F407 image under QEMU's netduinoplus2 (an STM32F405 model) and judges the run.

  check_boot.py [--qemu QEMU] [--timeout SECONDS] IMAGE.hex

The image is boot_probe.cpp's (the flash image's objects plus a probe; that file says how it
differs). QEMU loads the Intel hex into flash, as a flashing tool would, and fills the model's SRAM
with 0xA5 bytes before reset, so zeroed .bss and copied .data are the start-up code's work. The
run must end within the time limit with semihosting exit status 0, and:

  - the probe's report (stderr) has every fact below as PASS and none as FAIL;
  - every range the probe read through AdcRangers is the driver's scaling (adc_rangers.hpp: 4
    counts per centimetre, 2.5 mm per count, no echo below 80 or from 3060 counts) of the count the
    model's ADC gave: its data register yields 7 counts more at each conversion (QEMU's
    hw/adc/stm32f2xx_adc.c), 12 bits, from 0 at reset;
  - QEMU's log of accesses to the peripherals it leaves unimplemented (-d unimp: reads 0, writes
    ignored) shows the clock set-up switching the crystal on, polling RCC_CR for HSERDY until its
    bounded wait ran out and never switching to the PLL; the watchdog started and refreshed at
    least once per main-loop pass; CAN1 asked for initialisation mode and polled it until its
    bounded wait ran out, and the application's transmissions found no free mailbox; the camera
    interface (DCMI) set up.
"""
import argparse
import collections
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

SRAM_BASE, SRAM_BYTES = 0x20000000, 192 * 1024  # the model's SRAM (the chip has 128 KiB + 64 KiB CCM)
FILL = b"\xa5"
FACTS = ["data", "bss", "fill", "fpu", "vectors", "clock", "systick", "rangers", "main_loop"]

# adc_rangers.hpp's scaling and the model's ADC.
UM_PER_COUNT, MIN_COUNTS, MAX_COUNTS, NO_ECHO_UM = 2500, 20 * 4, 765 * 4, 0xFFFFFFFF
MODEL_STEP_COUNTS, ADC_MASK = 7, 0xFFF

UNIMP = re.compile(r"^(.+?): unimplemented device (read|write)\s+\(size \d+, offset 0x([0-9a-f]+)(?:, value 0x([0-9a-f]+))?\)")
WATCHDOG = ("IWDG", "I2S2ext")  # QEMU 7.2 maps both placeholders at 0x40003000; either may answer
RCC_CR, RCC_CFGR, HSEON, PLLON = 0x00, 0x08, 1 << 16, 1 << 24
KR_START, KR_RELOAD = 0xCCCC, 0xAAAA
CAN_MCR, CAN_MSR, CAN_TSR, INRQ = 0x00, 0x04, 0x08, 1 << 0
BOUNDED_WAIT_MIN_POLLS = 1000  # each bounded wait here is 200,000 polls; fewer than this did not wait


def expected_range_um(conversion):
    counts = (MODEL_STEP_COUNTS * conversion) & ADC_MASK
    return counts, (counts * UM_PER_COUNT if MIN_COUNTS <= counts < MAX_COUNTS else NO_ECHO_UM)


class Verdict:
    def __init__(self):
        self.failures = 0

    def check(self, ok, what):
        print(("ok    " if ok else "FAIL  ") + what)
        self.failures += not ok


def judge_report(lines, verdict):
    facts = {}
    for line in lines:
        m = re.match(r"^(PASS|FAIL) (\w+): (.*)$", line)
        if m:
            facts.setdefault(m.group(2), []).append((m.group(1), m.group(3)))
            print("  " + line)
    for name in FACTS:
        verdict.check(name in facts and all(v == "PASS" for v, _ in facts[name]), f"probe fact {name}")
    for name in sorted(set(facts) - set(FACTS)):
        verdict.check(all(v == "PASS" for v, _ in facts[name]), f"probe fact {name}")
    passes = 0
    if "main_loop" in facts:
        passes = int(facts["main_loop"][0][1].split()[0])
    return passes


def judge_ranges(lines, verdict):
    kinds = collections.Counter()
    wrong = []
    scans = 0
    for line in lines:
        if not line.startswith("RANGES "):
            continue
        fields = [int(f) for f in line.split()[1:]]
        scan, ranges = fields[0], fields[1:]
        scans += 1
        for beam, got in enumerate(ranges):
            conversion = 4 * scan + beam + 1
            counts, want = expected_range_um(conversion)
            if got != want:
                wrong.append(f"scan {scan} beam {beam}: {got} um, expected {want} um ({counts} counts)")
            kinds["below 20 cm" if counts < MIN_COUNTS else "765 cm and above" if counts >= MAX_COUNTS else "in range"] += 1
            kinds["after the 12-bit wrap"] += (MODEL_STEP_COUNTS * conversion) > ADC_MASK
    for w in wrong[:5]:
        print("  " + w)
    verdict.check(scans > 0 and not wrong, f"ranges of {scans} scans match the driver's scaling of the model's counts "
                  f"({', '.join(f'{n} {k}' for k, n in sorted(kinds.items()))})")
    verdict.check(all(kinds[k] > 0 for k in ("below 20 cm", "in range", "765 cm and above", "after the 12-bit wrap")),
                  "the scans covered both no-echo ends, the valid range and the ADC's wrap")


def judge_unimplemented(log, passes, verdict):
    reads = collections.Counter()
    writes = collections.defaultdict(list)
    rcc_cr_polls, hse_on = 0, False
    with log.open(encoding="utf-8", errors="replace") as f:
        for line in f:
            m = UNIMP.match(line)
            if not m:
                continue
            device, kind, offset = m.group(1), m.group(2), int(m.group(3), 16)
            device = "watchdog" if device in WATCHDOG else device
            if kind == "read":
                reads[(device, offset)] += 1
                rcc_cr_polls += device == "RCC" and offset == RCC_CR and hse_on
            else:
                value = int(m.group(4), 16)
                writes[(device, offset)].append(value)
                hse_on = hse_on or (device == "RCC" and offset == RCC_CR and value & HSEON != 0)
    rcc_cr = writes[("RCC", RCC_CR)]
    verdict.check(hse_on, "clock: RCC_CR written with HSEON (the crystal switched on)")
    verdict.check(rcc_cr_polls >= BOUNDED_WAIT_MIN_POLLS,
                  f"clock: {rcc_cr_polls} reads of RCC_CR after HSEON (the bounded HSERDY wait), then it went on")
    verdict.check(hse_on and not any(v & PLLON for v in rcc_cr) and not writes[("RCC", RCC_CFGR)],
                  "clock: the PLL never switched on and RCC_CFGR never written (it stayed on the HSI)")
    kr = writes[("watchdog", 0x00)]
    verdict.check(KR_START in kr, "watchdog: IWDG_KR written with the start key")
    verdict.check(passes > 0 and kr.count(KR_RELOAD) >= passes,
                  f"watchdog: {kr.count(KR_RELOAD)} reloads of IWDG_KR for {passes} main-loop passes")
    mcr = writes[("CAN1", CAN_MCR)]
    verdict.check(any(v & INRQ for v in mcr) and reads[("CAN1", CAN_MSR)] >= BOUNDED_WAIT_MIN_POLLS,
                  f"CAN1: initialisation requested, CAN_MSR polled {reads[('CAN1', CAN_MSR)]} times (bounded wait)")
    verdict.check(reads[("CAN1", CAN_TSR)] > 0,
                  f"CAN1: {reads[('CAN1', CAN_TSR)]} reads of CAN_TSR (transmissions offered, no free mailbox)")
    dcmi = sum(len(v) for (device, _), v in writes.items() if device == "DCMI")
    verdict.check(dcmi > 0, f"camera: {dcmi} writes to the DCMI registers (set up)")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--qemu", default="qemu-system-arm")
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds the run may take")
    ap.add_argument("image", type=pathlib.Path, help="the image as Intel hex")
    args = ap.parse_args()
    qemu = shutil.which(args.qemu)
    if qemu is None:
        sys.exit(f"check_boot: {args.qemu} not found (toolchain/setup-debian.sh installs qemu-system-arm)")
    if not args.image.is_file():
        sys.exit(f"check_boot: no image {args.image}")

    verdict = Verdict()
    with tempfile.TemporaryDirectory(prefix="stm32f4_boot_") as tmp:
        fill, log = pathlib.Path(tmp, "sram.bin"), pathlib.Path(tmp, "unimp.log")
        fill.write_bytes(FILL * SRAM_BYTES)
        command = [qemu, "-M", "netduinoplus2", "-nographic", "-monitor", "none", "-serial", "none",
                   "-semihosting-config", "enable=on,target=native",
                   "-device", f"loader,file={fill},addr={SRAM_BASE:#x}", "-device", f"loader,file={args.image}",
                   "-d", "unimp", "-D", str(log)]
        try:
            run = subprocess.run(command, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=args.timeout)
        except subprocess.TimeoutExpired as e:
            out = (e.stderr or b"").decode(errors="replace") if isinstance(e.stderr, bytes) else (e.stderr or "")
            print(out)
            sys.exit(f"check_boot: FAIL, no exit within {args.timeout} s (a hang, or a fault with no report)")
        lines = (run.stdout + run.stderr).splitlines()
        verdict.check(run.returncode == 0, f"QEMU exit status {run.returncode} (0: the probe's semihosting exit, all facts)")
        passes = judge_report(lines, verdict)
        judge_ranges(lines, verdict)
        judge_unimplemented(log, passes, verdict)
        for line in lines:
            if not re.match(r"^(PASS|FAIL|RANGES|DONE) ", line) and line.strip():
                print("  qemu: " + line)
    print(f"check_boot: {'FAIL' if verdict.failures else 'ok'}, {verdict.failures} failed checks")
    sys.exit(1 if verdict.failures else 0)


if __name__ == "__main__":
    main()
