#!/bin/sh
# A fake `adb`: a test double for playback phones that run a SiTAR playback app.
# It refuses what a phone and the shipped apps would refuse (docs/playback-contract.md):
#   am start -S -W -n PACKAGE/ACTIVITY --ei trials N --ei first F
#            --es recording FILE --es output DIR
# exactly these options and extras; an installed activity (else am's own
# "Error: Activity class … does not exist." on stdout, exit 0, as the real am);
# FILE pushed before; FILE and DIR inside the app's own external files folder
# /sdcard/Android/data/PACKAGE/files (the only place the app may touch without a
# storage permission). The fake app then writes DIR/trajectory_{F+k}.txt (a
# `.part` name renamed into place) and a one-line DIR/status.txt.
#
# Phones are directories $FAKE_ADB_ROOT/phones/SERIAL (their file system under it).
# SERIAL/.installed lists the installed activities, one PACKAGE/ACTIVITY a line.
# A phone with a file .lost is gone; with .lose_after N it is lost after N trials;
# with .hang its playback app never finishes a trial; with .fail the app reports
# `failed <the file's text>` in its status file after starting.
# Trials come from $FAKE_ADB_ROOT/pool/trial_K.txt in order (K from $FAKE_ADB_ROOT/counter).
R="$FAKE_ADB_ROOT"
die() { echo "fake adb: $*" >&2; exit 1; }
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
[ "$1" = "-s" ] || die "expected -s SERIAL, got $*"
S="$2"; shift 2
P="$R/phones/$S"
if [ ! -d "$P" ] || [ -e "$P/.lost" ]; then echo "error: device '$S' not found" >&2; exit 1; fi
echo "$S $*" >> "$R/log"

# am start with the contract's options and extras; sets COMP TRIALS FIRST REC OUT.
parse_am_start() {
  S_FLAG=; W_FLAG=; COMP=; TRIALS=; FIRST=; REC=; OUT=
  while [ $# -gt 0 ]; do
    case "$1" in
      -S) S_FLAG=1; shift ;;
      -W) W_FLAG=1; shift ;;
      -n) [ $# -ge 2 ] || die "am start -n without a component"; COMP="$2"; shift 2 ;;
      --ei)
        [ $# -ge 3 ] || die "am start --ei needs a name and a value"
        case "$3" in ''|*[!0-9]*) die "am start --ei $2 $3: not a non-negative integer" ;; esac
        case "$2" in
          trials) TRIALS="$3" ;;
          first) FIRST="$3" ;;
          *) die "am start: the playback apps read no int extra '$2'" ;;
        esac
        shift 3 ;;
      --es)
        [ $# -ge 3 ] || die "am start --es needs a name and a value"
        case "$2" in
          recording) REC="$3" ;;
          output) OUT="$3" ;;
          *) die "am start: the playback apps read no string extra '$2'" ;;
        esac
        shift 3 ;;
      *) die "am start: unexpected argument '$1'" ;;
    esac
  done
  [ -n "$S_FLAG" ] || die "am start without -S: a run still going on the phone would get onNewIntent"
  [ -n "$W_FLAG" ] || die "am start without -W"
  [ -n "$COMP" ] || die "am start without -n PACKAGE/ACTIVITY"
  for v in TRIALS FIRST REC OUT; do
    eval "[ -n \"\$$v\" ]" || die "am start without the extra for $v"
  done
}

case "$1" in
  push) mkdir -p "$P$(dirname "$3")" && cp "$2" "$P$3" ;;
  pull) cp "$P$2" "$3" ;;
  shell)
    shift
    case "$1" in
      mkdir) [ "$2" = "-p" ] || die "mkdir without -p"; mkdir -p "$P$3" ;;
      rm)
        shift
        [ "$1" = "-f" ] && shift
        for pattern in "$@"; do for f in $P$pattern; do rm -f "$f"; done; done ;;
      ls) ls "$P$2" ;;
      cat) cat "$P$2" ;;
      am)
        if [ "$2" = "force-stop" ]; then
          [ -f "$P/.pid" ] && kill "$(cat "$P/.pid")" 2>/dev/null
          rm -f "$P/.pid"
          exit 0
        fi
        [ "$2" = "start" ] || die "unknown am command $2"
        shift 2
        parse_am_start "$@"
        if ! grep -qxF "$COMP" "$P/.installed" 2>/dev/null; then
          echo "Starting: Intent { cmp=$COMP }"
          echo "Error type 3"
          echo "Error: Activity class {$COMP} does not exist."
          exit 0
        fi
        PKG="${COMP%%/*}"
        FILES="/sdcard/Android/data/$PKG/files"
        case "$REC" in "$FILES"/*) ;; *) die "recording $REC is outside $FILES, which $PKG cannot read" ;; esac
        case "$OUT" in "$FILES"/*) ;; *) die "output $OUT is outside $FILES, which $PKG cannot write" ;; esac
        [ -f "$P$REC" ] || die "recording $REC was not pushed"
        # -S: the running app is stopped first.
        [ -f "$P/.pid" ] && kill "$(cat "$P/.pid")" 2>/dev/null
        rm -f "$P/.pid"
        mkdir -p "$P$OUT"
        status() { printf '%s\n' "$1" > "$P$OUT/.status.part" && mv "$P$OUT/.status.part" "$P$OUT/status.txt"; }
        status starting
        echo "Starting: Intent { cmp=$COMP }"
        echo "Status: ok"
        echo "Activity: $COMP"
        echo "Complete"
        # A hung playback app: starts, never writes a trajectory.
        if [ -e "$P/.hang" ]; then status "playing 1/$TRIALS"; exit 0; fi
        (
          if [ -e "$P/.fail" ]; then
            sleep "${FAKE_TRIAL_SECONDS:-0.2}"
            status "failed $(cat "$P/.fail")"
            exit 0
          fi
          i=0
          while [ "$i" -lt "$TRIALS" ]; do
            status "playing $((i + 1))/$TRIALS"
            sleep "${FAKE_TRIAL_SECONDS:-0.2}"
            [ -e "$P/.lost" ] && exit 0
            while ! mkdir "$R/lock" 2>/dev/null; do sleep 0.01; done
            k=$(cat "$R/counter"); echo $((k + 1)) > "$R/counter"; rmdir "$R/lock"
            n=$((FIRST + i))
            cp "$R/pool/trial_$k.txt" "$P$OUT/trajectory_$n.txt.part" && mv "$P$OUT/trajectory_$n.txt.part" "$P$OUT/trajectory_$n.txt"
            i=$((i + 1))
            if [ -f "$P/.lose_after" ] && [ "$i" -ge "$(cat "$P/.lose_after")" ]; then touch "$P/.lost"; exit 0; fi
          done
          status "done $TRIALS/$TRIALS"
        ) > /dev/null 2>&1 &
        echo $! > "$P/.pid"
        ;;
      *) die "unknown shell command $*" ;;
    esac
    ;;
  *) die "unknown command $*" ;;
esac
