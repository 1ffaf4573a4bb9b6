#!/bin/busybox sh
# /init of the test VM (tests/vm/vm_test.sh): loads the CAN modules, makes vcan0, and runs the
# native firmware, our host client and can-utils against each other. Prints one
# "VMTEST ok|FAIL <name>" line per check, then "VMTEST DONE", then powers off.
/bin/busybox --install -s /bin
export PATH=/bin:/usr/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mount -t tmpfs tmp /tmp
export ASAN_OPTIONS=detect_leaks=0  # leaks are checked by the native test run; LSan needs ptrace here
# Progress on the console as it happens, with seconds since boot, so a run cut off by its timeout
# shows the step it stopped in.
step() { echo "VMTEST step $1 at $(cut -d' ' -f1 /proc/uptime) s"; }
ok() { echo "VMTEST ok $1"; }
bad() { echo "VMTEST FAIL $1"; }
show() { echo "---- $1"; cat "$1"; echo "----"; }

step "init: loading the CAN modules"
for m in can can-raw can-isotp can-dev vcan; do insmod /modules/$m.ko || bad "insmod_$m"; done
ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 && ip link set up vcan0 && ok vcan0_up || bad vcan0_up

# Readiness is waited for, never slept for: on a busy machine the emulated, sanitized programs
# need seconds to start, and a frame sent before a socket is bound is lost.
# listening PID: waits (at most 20 s) until process PID has a CAN socket open.
listening() {
  i=0
  while [ $i -lt 200 ]; do
    ls -l "/proc/$1/fd" 2>/dev/null | grep -q "socket:" && { sleep 0.1; return 0; }
    sleep 0.1
    i=$((i + 1))
  done
  echo "VMTEST note: process $1 opened no socket within 20 s"
}
platform() {  # starts the native firmware and waits until it runs; $@ = extra options
  : >/tmp/platform.err  # emptied here: the background start truncates it only some time later
  kincal_platform --can vcan0 --storage /tmp/store "$@" 2>/tmp/platform.err &
  PLATFORM=$!
  i=0
  while [ $i -lt 300 ] && ! grep -q "running on" /tmp/platform.err; do
    sleep 0.1
    i=$((i + 1))
  done
  grep -q "running on" /tmp/platform.err || { show /tmp/platform.err; bad platform_starts; }
}
stop_platform() {
  kill "$PLATFORM"
  wait "$PLATFORM" && grep -q "stopped" /tmp/platform.err && ok "$1" || { show /tmp/platform.err; bad "$1"; }
}
# expect_frame NAME CANDUMP_FILTER PATTERN COMMAND...: runs COMMAND and checks that candump sees
# a frame matching PATTERN (candump -L format) within 10 s.
expect_frame() {
  name=$1 filter=$2 pattern=$3
  shift 3
  candump -L -n 1 -T 10000 "vcan0,$filter" >/tmp/expect.txt &
  C=$!
  listening $C
  "$@"
  wait $C
  grep -q "$pattern" /tmp/expect.txt && ok "$name" || { show /tmp/expect.txt; bad "$name"; }
}

# 1. Our platform and our client through the whole scenario, classic CAN then CAN FD; candump logs.
step "1: platform and client, classic CAN then CAN FD"
candump -L vcan0 >/tmp/session.log &
CANDUMP=$!
listening $CANDUMP
platform
step "1a: kincal exercise, classic CAN"
kincal exercise --can vcan0 --measurements 10 --corrections 200 --correction-timeout-ms 3000 >/tmp/ex1.txt 2>&1 && ok scenario_classic ||
  { show /tmp/ex1.txt; bad scenario_classic; }
stop_platform platform_stops_cleanly
platform --fd
step "1b: kincal exercise, CAN FD"
kincal exercise --can vcan0 --fd --measurements 10 --corrections 200 --correction-timeout-ms 3000 >/tmp/ex2.txt 2>&1 && ok scenario_fd ||
  { show /tmp/ex2.txt; bad scenario_fd; }
# The parameters uploaded in round 1 were loaded from storage by the restarted platform:
# only the colour LUT and geometry flags (0x6) remain in its first heartbeat.
grep -q "heartbeat state=idle protocol 3.0 error_flags=0x6" /tmp/ex2.txt && ok parameters_survive_restart ||
  bad parameters_survive_restart
stop_platform platform_stops_cleanly_fd
kill $CANDUMP
sleep 0.2
head -3 /tmp/ex1.txt
grep "median round trip" /tmp/ex1.txt /tmp/ex2.txt

# 2. candump's log decodes with our reader and monitor, completely.
step "2: the candump log through our reader and monitor"
kincal monitor --replay /tmp/session.log >/tmp/monitor.txt 2>&1 && tail -1 /tmp/monitor.txt | grep -q " 0 malformed" &&
  [ "$(wc -l </tmp/session.log)" -gt 800 ] && ok candump_log_decodes || { tail -5 /tmp/monitor.txt; bad candump_log_decodes; }
grep -q "MeasurementReport seq=" /tmp/monitor.txt && grep -q "ParameterWrite block=4" /tmp/monitor.txt &&
  grep -q "CorrectedFd" /tmp/monitor.txt && ok monitor_decodes_messages || bad monitor_decodes_messages
echo "candump log: $(wc -l </tmp/session.log) frames; $(tail -1 /tmp/monitor.txt)"

# 3. can-utils as independent ISO-TP peers of the firmware's ISO-TP (padding 0xCC).
step "3: can-utils ISO-TP peers"
platform
expect_frame isotpsend_to_platform 130:7FF "130#01" sh -c "isotpsend -s 150 -d 158 -p CC vcan0 </vm/intrinsics_write.hex"
timeout 15 isotprecv -s 150 -d 158 -p CC vcan0 >/tmp/recv.txt &
R=$!
listening $R
echo "02 01" | isotpsend -s 150 -d 158 -p CC vcan0
wait $R
# ParameterData 0x82, block 1, format version 4 (shared/parameters.hpp kBlockFormatVersion), 40 bytes.
grep -q "^82 01 04 00 28 00" /tmp/recv.txt && ok platform_to_isotprecv || { show /tmp/recv.txt; bad platform_to_isotprecv; }
cmp -s /tmp/recv.txt /vm/intrinsics_data.txt && ok isotprecv_bytes_exact || { show /tmp/recv.txt; bad isotprecv_bytes_exact; }

# 4. Injected frames get defined responses (ErrorReport 0x140, reason in the first byte).
step "4: injected frames"
expect_frame wrong_length 140:7FF "140#02" cansend vcan0 100#0100
expect_frame unknown_id 140:7FF "140#01" cansend vcan0 17E#00
expect_frame reserved_bits 140:7FF "140#04" cansend vcan0 100#80
expect_frame isotp_out_of_sequence 140:7FF "140#09" sh -c "cansend vcan0 150#1020010203040506; cansend vcan0 150#2301020304050607"
expect_frame unknown_message 140:7FF "140#0C" cansend vcan0 150#017E
expect_frame joint_not_in_mode 140:7FF "140#06" cansend vcan0 110#0000000000000000
candump -L -T 1000 vcan0,140:7FF >/tmp/other.txt &
C=$!
listening $C
cansend vcan0 7FF#00  # another node's traffic: no response at all
cansend vcan0 050#0102
wait $C
grep -q "140#" /tmp/other.txt && bad foreign_ids_ignored || ok foreign_ids_ignored

# 5. A flood of 20,000 malformed frames: reports stay rate-limited, the platform keeps working.
step "5: a flood of malformed frames"
candump -L vcan0,140:7FF >/tmp/flood.txt &
C=$!
listening $C
start=$(date +%s)
cangen vcan0 -I 110 -L 3 -g 0 -i -n 20000
end=$(date +%s)
sleep 0.5
kill $C
reports=$(grep -c "140#" /tmp/flood.txt)
echo "flood: 20000 frames in $((end - start + 1)) s or less, $reports error reports"
[ "$reports" -ge 1 ] && [ "$reports" -le $(((end - start + 2) * 100 + 5)) ] && ok flood_reports_rate_limited ||
  bad flood_reports_rate_limited
kincal exercise --can vcan0 --measurements 2 --corrections 20 --correction-timeout-ms 3000 >/tmp/ex3.txt 2>&1 && ok platform_alive_after_flood ||
  { show /tmp/ex3.txt; bad platform_alive_after_flood; }
stop_platform platform_stops_cleanly_after_flood

# 6. A live camera: the kernel's virtual capture driver vivid as /dev/video0 (capture node only);
#    kincal_platform --camera streams from it and answers a blob measurement without a camera
#    failure; then the device is unbound (a camera unplugged mid-stream): the next measurement
#    reports a camera failure and the platform keeps answering.
step "6: live V4L2 camera (vivid)"
for m in mc videodev v4l2-dv-timings videobuf2-common videobuf2-memops videobuf2-v4l2 videobuf2-vmalloc \
  videobuf2-dma-contig v4l2-tpg rc-core cec; do insmod /modules/$m.ko || bad "insmod_$m"; done
insmod /modules/vivid.ko n_devs=1 node_types=0x1 && [ -c /dev/video0 ] && ok vivid_video0 || bad vivid_video0
platform --camera /dev/video0
grep -q "camera /dev/video0 ('vivid" /tmp/platform.err && ok camera_streams || { show /tmp/platform.err; bad camera_streams; }
# measure SEQ FILE: a blob measurement (sections 0x10) with its report decoded by our monitor.
measure() {
  candump -L vcan0 >/tmp/camera.log &
  C=$!
  listening $C
  timeout 20 isotprecv -s 150 -d 158 -p CC vcan0 >/dev/null &
  R=$!
  listening $R
  cansend vcan0 "120#${1}10"
  wait $R
  # candump may log the report's last frame after isotprecv has it: wait (at most 10 s) for it.
  i=0
  while [ $i -lt 20 ] && ! kincal monitor --replay /tmp/camera.log 2>&1 | grep "MeasurementReport seq=$((0x$1))" >"$2"; do
    sleep 0.5
    i=$((i + 1))
  done
  kill $C
  wait $C 2>/dev/null
}
cansend vcan0 100#01  # ModeCommand: measurement triggers accepted
measure 01 /tmp/camera1.txt
grep -q "sections=0x10 blobs=" /tmp/camera1.txt && ! grep -q "camera failure" /tmp/camera1.txt &&
  ok camera_measurement || { show /tmp/camera1.txt; show /tmp/platform.err; bad camera_measurement; }
cat /tmp/camera1.txt
basename "$(ls -d /sys/bus/platform/drivers/vivid/vivid*)" >/sys/bus/platform/drivers/vivid/unbind && ok vivid_unplugged || bad vivid_unplugged
measure 02 /tmp/camera2.txt
grep -q "status=camera failure" /tmp/camera2.txt && grep -q "camera /dev/video0: .*unplugged" /tmp/platform.err &&
  ok camera_unplugged_reported || { show /tmp/camera2.txt; show /tmp/platform.err; bad camera_unplugged_reported; }
kincal exercise --can vcan0 --measurements 1 --corrections 10 --correction-timeout-ms 3000 >/tmp/ex4.txt 2>&1 &&
  ok platform_alive_after_unplug || { show /tmp/ex4.txt; bad platform_alive_after_unplug; }
stop_platform platform_stops_cleanly_after_unplug

# 7. A platform set up from files (kincal platform load / show): with an empty store show names
#    both blocks missing (exit 1); load uploads the camera calibration and platform.yaml and reads
#    them back; after a restart (on CAN FD) the platform still holds them.
step "7: kincal platform load / show"
rm -f /tmp/store/*
platform
kincal platform show --can vcan0 >/tmp/show1.txt 2>&1
[ $? -eq 1 ] && grep -q "camera: not loaded" /tmp/show1.txt && grep -q "geometry: not loaded" /tmp/show1.txt &&
  ok platform_show_missing || { show /tmp/show1.txt; bad platform_show_missing; }
kincal platform load --can vcan0 --camera /vm/camera.yaml --geometry /vm/platform.yaml >/tmp/load.txt 2>&1 &&
  grep -q "camera: 640 x 480 px, fx 600 fy 600 cx 319.5 cy 239.5 px" /tmp/load.txt &&
  grep -q "square pitch: 0.1016 m" /tmp/load.txt && ok platform_load || { show /tmp/load.txt; bad platform_load; }
cat /tmp/load.txt
stop_platform platform_stops_cleanly_after_load
platform --fd
kincal platform show --can vcan0 --fd >/tmp/show2.txt 2>&1 && grep -q "distortion k1 -0.05 k2 0.01" /tmp/show2.txt &&
  grep -q "ranger 2: origin (-0.05, 0, 0) direction (0, 0, 1)" /tmp/show2.txt &&
  ok platform_show_after_restart || { show /tmp/show2.txt; bad platform_show_after_restart; }
stop_platform platform_stops_cleanly_after_show

step done
echo "VMTEST DONE"
poweroff -f
