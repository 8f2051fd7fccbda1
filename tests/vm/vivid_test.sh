#!/usr/bin/env bash
# tests/vm/vivid_test.sh - the V4L2 source against a real kernel driver: boots Debian's kernel
# under qemu with a small initramfs, loads vivid with 4 capture devices and runs the static
# capture program on all four at once, then the daemon (if given), then the capture again with
# faults injected through vivid's controls (dropped frames, a camera unplugged and back, a camera stalled and back); results
# come back over the second serial port. The exit code is the test result (0 pass, 1 fail, 2 cannot run).
#
#   tests/vm/vivid_test.sh VMDIR CAPTURE [DAEMON CONFIG]
#
# VMDIR    work folder ($(BUILD)/vm): the initramfs and the guest's results
# The kernel package (downloaded once with `apt-get download`, never installed) and the unpacked
# kernel and media modules are cached in $RP_VM_CACHE (default ${XDG_CACHE_HOME:-~/.cache}/
# rigpose/vm), which `make clean` does not remove.
# CAPTURE  static vivid_capture (tests/vm/vivid_capture.c)
# DAEMON   optional daemon, run as `DAEMON --config CONFIG --frames 15` in the guest after the
#          capture, then with CONFIG's back pair at 15 fps and source.sets: latest (free-running
#          cameras at two rates) for 30 sets; static, or dynamic with its shared libraries (from ldd) copied into the
#          initramfs (Debian ships no static liblcm). CONFIG should publish to a file:// log
#          under /tmp; the test checks the daemon's exit code and that the log is not empty.
# Needs: qemu-system-x86_64, busybox (static), xz, dpkg-deb, apt-get (scripts/install-deps.sh);
# no root. Environment: RP_VM_SETS (frame sets to capture, 50), RP_VM_TIMEOUT (s, 300).
set -u
VMDIR=${1:?usage: vivid_test.sh VMDIR CAPTURE [DAEMON CONFIG]}
CAPTURE=${2:?usage: vivid_test.sh VMDIR CAPTURE [DAEMON CONFIG]}
DAEMON=${3:-}
DCONFIG=${4:-}
SETS=${RP_VM_SETS:-50}
TIMEOUT=${RP_VM_TIMEOUT:-300}

say() { echo "vivid_test: $*"; }
die() { say "FAIL: $*"; exit 1; }
cant() { say "CANNOT RUN: $*"; exit 2; }

for tool in qemu-system-x86_64 xz dpkg-deb apt-get apt-cache cpio; do
  command -v "$tool" >/dev/null || cant "$tool not found (scripts/install-deps.sh installs it)"
done
BUSYBOX=/bin/busybox
[ -x "$BUSYBOX" ] || cant "$BUSYBOX missing (Debian busybox-static)"
if ldd "$BUSYBOX" >/dev/null 2>&1; then cant "$BUSYBOX is dynamic; the guest needs busybox-static"; fi
[ -x "$CAPTURE" ] || cant "capture program $CAPTURE not built"
mkdir -p "$VMDIR" || cant "cannot create $VMDIR"
VMDIR=$(cd "$VMDIR" && pwd)

# ---- kernel and modules, cached ----------------------------------------------------------------
CACHE=${RP_VM_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/rigpose/vm}
mkdir -p "$CACHE" || cant "cannot create the cache folder $CACHE"
KDIR=$CACHE/kernel
exec 9>"$CACHE/.lock" && flock 9 || cant "cannot lock $CACHE/.lock"  # one preparer at a time
if [ ! -f "$KDIR/ready" ]; then
  pkg=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/{print $2; exit}')
  [ -n "$pkg" ] || cant "apt-cache names no linux-image-* for linux-image-amd64 (apt-get update?)"
  deb=$(ls "$CACHE"/"${pkg}"_*.deb 2>/dev/null | head -1)
  if [ -z "$deb" ]; then
    say "downloading $pkg (about 70 MB, once, into $CACHE)"
    (cd "$CACHE" && apt-get download "$pkg" >/dev/null 2>&1) || cant "apt-get download $pkg failed"
    deb=$(ls "$CACHE"/"${pkg}"_*.deb 2>/dev/null | head -1)
    [ -n "$deb" ] || cant "apt-get download $pkg left no .deb in $CACHE"
  fi
  say "unpacking $(basename "$deb")"
  rm -rf "$KDIR" && mkdir -p "$KDIR/root"
  dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$KDIR/root" --wildcards \
      './boot/vmlinuz-*' './lib/modules/*/modules.*' './lib/modules/*/kernel/drivers/media/*' \
      || cant "cannot unpack $deb"
  vmlinuz=$(ls "$KDIR"/root/boot/vmlinuz-* | head -1)
  KVER=$(basename "$vmlinuz"); KVER=${KVER#vmlinuz-}
  # The bzImage holds an xz stream: boot the plain vmlinux straight (faster than the BIOS path).
  off=$(LC_ALL=C grep -obUaP '\xfd7zXZ\x00' "$vmlinuz" | head -1 | cut -d: -f1)
  [ -n "$off" ] || cant "no xz stream in $vmlinuz"
  tail -c +$((off + 1)) "$vmlinuz" | xz -dc > "$KDIR/vmlinux" 2>/dev/null
  [ -s "$KDIR/vmlinux" ] || cant "could not decompress the kernel"
  "$BUSYBOX" depmod -b "$KDIR/root" "$KVER" || cant "busybox depmod failed"
  echo "$KVER" > "$KDIR/kver"
  touch "$KDIR/ready"
fi
flock -u 9
KVER=$(cat "$KDIR/kver")
MODROOT=$KDIR/root/lib/modules/$KVER
[ -f "$MODROOT/modules.dep" ] || cant "no modules.dep in $MODROOT"

# ---- initramfs ---------------------------------------------------------------------------------
WORK=$VMDIR/run
rm -rf "$WORK" && mkdir -p "$WORK/root"/{bin,proc,sys,dev,tmp,etc} "$WORK/root/lib/modules/$KVER"
R=$WORK/root
cp "$BUSYBOX" "$R/bin/busybox"
cp "$CAPTURE" "$R/bin/vivid_capture"
# vivid and what it needs, from modules.dep (lines "path: dep dep ...").
need=$(awk -F': *' -v m='/vivid.ko' 'index($1, m) { print $1; n = split($2, d, " "); for (i = 1; i <= n; i++) print d[i] }' \
       "$MODROOT/modules.dep")
[ -n "$need" ] || cant "vivid is not in $MODROOT/modules.dep"
for m in $need; do
  mkdir -p "$R/lib/modules/$KVER/$(dirname "$m")"
  cp "$MODROOT/$m" "$R/lib/modules/$KVER/$m"
  grep "^$m:" "$MODROOT/modules.dep" >> "$R/lib/modules/$KVER/modules.dep"
done
DAEMON_CMD=""
if [ -n "$DAEMON" ]; then
  [ -x "$DAEMON" ] || cant "daemon $DAEMON not built"
  [ -f "$DCONFIG" ] || cant "daemon configuration $DCONFIG missing"
  cp "$DAEMON" "$R/bin/rigpose"
  cp "$DCONFIG" "$R/etc/rig.yaml"
  # Free-running cameras at two rates (issue 15): the back pair at 15 fps, the front at 25
  # (vivid gives what it can: best effort), sets made by cam1's frames (source.sets: latest).
  awk '/^  retry_ms:/ { print; print "  sets: latest"; next }
       /^    fps: 25/ { n++; if (n > 2) { print "    fps: 15"; next } } { print }' \
      "$DCONFIG" > "$R/etc/rig_latest.yaml"
  grep -q '^  sets: latest' "$R/etc/rig_latest.yaml" || cant "could not derive rig_latest.yaml"
  # Shared libraries at their host paths (the loader included), if the daemon is dynamic.
  for lib in $(ldd "$DAEMON" 2>/dev/null | grep -oE '/[^ ]+\.so[^ ]*'); do
    mkdir -p "$R$(dirname "$lib")"
    cp -L "$lib" "$R$lib"
  done
  DAEMON_CMD="run_daemon"
fi
cat > "$R/init" <<INIT
#!/bin/busybox sh
/bin/busybox --install -s /bin
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
out=/dev/ttyS1
echo "guest: kernel \$(uname -r)" > \$out
if ! modprobe vivid n_devs=4 node_types=0x1,0x1,0x1,0x1 num_inputs=1,1,1,1 input_types=0,0,0,0 > /tmp/mod.log 2>&1; then
  echo "FAIL: modprobe vivid: \$(cat /tmp/mod.log)" > \$out; poweroff -f
fi
i=0; while [ ! -e /dev/video3 ] && [ \$i -lt 50 ]; do sleep 0.1; i=\$((i + 1)); done
echo "guest: devices \$(ls /dev/video* | tr '\n' ' ')" > \$out
/bin/vivid_capture --sets $SETS /dev/video0 /dev/video1 /dev/video2 /dev/video3 > \$out 2>&1
echo "capture_exit=\$?" > \$out
run_daemon() {
  cd /tmp && /bin/rigpose --config /etc/rig.yaml --frames 15 > /tmp/daemon.log 2>&1
  echo "daemon_exit=\$?" > \$out
  tail -n 8 /tmp/daemon.log > \$out
  echo "daemon_lcm_log_bytes=\$(wc -c < /tmp/rigpose.lcmlog 2>/dev/null || echo 0)" > \$out
  rm -f /tmp/rigpose.lcmlog
  /bin/rigpose --config /etc/rig_latest.yaml --frames 30 > /tmp/daemon2.log 2>&1
  echo "daemon_latest_exit=\$?" > \$out
  tail -n 8 /tmp/daemon2.log > \$out
  echo "daemon_latest_lcm_log_bytes=\$(wc -c < /tmp/rigpose.lcmlog 2>/dev/null || echo 0)" > \$out
}
$DAEMON_CMD
echo "guest: faults (320x180, lighter on a busy host): 50 % of cam1's frames dropped by the driver; cam3 unplugged before set 20 and plugged back; cam2 stalled (no frames) before set 60 for 20 sets" > \$out
/bin/vivid_capture --sets 100 --size 320x180 --drop-perc 1:50 --disconnect 3:20 --stall 2:60:20 /dev/video0 /dev/video1 /dev/video2 /dev/video3 > \$out 2>&1
echo "fault_exit=\$?" > \$out
echo "guest: done" > \$out
poweroff -f
INIT
chmod +x "$R/init"
(cd "$R" && find . | "$BUSYBOX" cpio -o -H newc -R 0:0 2>/dev/null) > "$WORK/initrd.cpio" \
    || cant "cpio failed"

# ---- boot --------------------------------------------------------------------------------------
accel="-accel tcg,thread=multi -cpu max"
if grep -qwE 'vmx|svm' /proc/cpuinfo && [ -w /dev/kvm ]; then accel="-accel kvm -cpu host"; fi
say "booting $KVER ($accel), capturing $SETS sets from 4 vivid devices"
t0=$(date +%s.%N)
timeout --kill-after=10 "$TIMEOUT" qemu-system-x86_64 $accel -machine q35 -m 512 -smp 1 \
    -kernel "$KDIR/vmlinux" -initrd "$WORK/initrd.cpio" \
    -append "console=ttyS0 rdinit=/init panic=-1 quiet loglevel=3" \
    -display none -monitor none -nodefaults -no-reboot \
    -serial "file:$WORK/console.log" -serial "file:$WORK/results.log"
qrc=$?
t1=$(date +%s.%N)
tr -d '\r' < "$WORK/results.log" > "$WORK/results.txt" 2>/dev/null
sed 's/^/  guest| /' "$WORK/results.txt"
say "VM ran $(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }') s"
if [ $qrc -eq 124 ] || [ $qrc -eq 137 ]; then
  say "console tail:"; tail -n 20 "$WORK/console.log" | tr -d '\r' | sed 's/^/  console| /'
  die "qemu did not finish within ${TIMEOUT}s"
fi
[ $qrc -eq 0 ] || die "qemu exited with $qrc (console: $WORK/console.log)"
grep -qx 'guest: done' "$WORK/results.txt" || {
  tail -n 20 "$WORK/console.log" | tr -d '\r' | sed 's/^/  console| /'; die "the guest did not finish its script"; }
grep -qx 'capture_exit=0' "$WORK/results.txt" && grep -qx 'PASS' "$WORK/results.txt" \
    || die "capture inside the VM failed (see the guest lines above)"
grep -qx 'fault_exit=0' "$WORK/results.txt" \
    || die "capture with injected drops and an unplugged camera failed (see the guest lines above)"
if [ -n "$DAEMON" ]; then
  grep -qx 'daemon_exit=0' "$WORK/results.txt" || die "the daemon inside the VM failed"
  bytes=$(sed -n 's/^daemon_lcm_log_bytes=//p' "$WORK/results.txt")
  [ "${bytes:-0}" -gt 0 ] || die "the daemon inside the VM published nothing (empty LCM log)"
  grep -qx 'daemon_latest_exit=0' "$WORK/results.txt" \
      || die "the daemon with free-running cameras at 25 and 15 fps (sets: latest) failed"
  bytes=$(sed -n 's/^daemon_latest_lcm_log_bytes=//p' "$WORK/results.txt")
  [ "${bytes:-0}" -gt 0 ] || die "the daemon with sets: latest published nothing"
fi
say "PASS"
exit 0
