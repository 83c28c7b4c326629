#!/bin/sh
# A fake `adb` that behaves like playback phones, for the adb backend's tests.
# Phones are directories $FAKE_ADB_ROOT/phones/SERIAL (their file system under it).
# A phone with a file .lost is gone; with .lose_after N it is lost after N trials;
# with .hang its playback app never finishes a trial.
# Trials come from $FAKE_ADB_ROOT/pool/trial_K.txt in order (K from $FAKE_ADB_ROOT/counter).
R="$FAKE_ADB_ROOT"
if [ "$1" = "devices" ]; then
  echo "List of devices attached"
  for d in "$R"/phones/*; do
    [ -d "$d" ] || continue
    [ -e "$d/.lost" ] && continue
    printf '%s\tdevice\n' "$(basename "$d")"
  done
  echo
  exit 0
fi
[ "$1" = "-s" ] || { echo "fake adb: expected -s SERIAL, got $*" >&2; exit 1; }
S="$2"; shift 2
P="$R/phones/$S"
if [ ! -d "$P" ] || [ -e "$P/.lost" ]; then echo "error: device '$S' not found" >&2; exit 1; fi
echo "$S $*" >> "$R/log"
case "$1" in
  push) mkdir -p "$P$(dirname "$3")" && cp "$2" "$P$3" ;;
  pull) cp "$P$2" "$3" ;;
  shell)
    shift
    case "$1" in
      mkdir) mkdir -p "$P$3" ;;
      rm) for f in $P$3; do rm -f "$f"; done ;;
      ls) ls "$P$2" ;;
      am)
        if [ "$2" = "force-stop" ]; then
          [ -f "$P/.pid" ] && kill "$(cat "$P/.pid")" 2>/dev/null
          exit 0
        fi
        # am start -n COMPONENT --ei trials N --es recording FILE --es output DIR
        N="$7"; OUT="${13}"
        [ -f "$P${10}" ] || { echo "fake adb: recording ${10} was not pushed" >&2; exit 1; }
        # A hung playback app: starts, never writes a trajectory.
        if [ -e "$P/.hang" ]; then echo "Starting: Intent { cmp=$4 }"; exit 0; fi
        (
          i=0
          while [ "$i" -lt "$N" ]; do
            sleep "${FAKE_TRIAL_SECONDS:-0.2}"
            [ -e "$P/.lost" ] && exit 0
            while ! mkdir "$R/lock" 2>/dev/null; do sleep 0.01; done
            k=$(cat "$R/counter"); echo $((k + 1)) > "$R/counter"; rmdir "$R/lock"
            cp "$R/pool/trial_$k.txt" "$P$OUT/.part_$i" && mv "$P$OUT/.part_$i" "$P$OUT/trajectory_$i.txt"
            i=$((i + 1))
            if [ -f "$P/.lose_after" ] && [ "$i" -ge "$(cat "$P/.lose_after")" ]; then touch "$P/.lost"; exit 0; fi
          done
        ) > /dev/null 2>&1 &
        echo $! > "$P/.pid"
        echo "Starting: Intent { cmp=$4 }"
        ;;
      *) echo "fake adb: unknown shell command $*" >&2; exit 1 ;;
    esac
    ;;
  *) echo "fake adb: unknown command $*" >&2; exit 1 ;;
esac
