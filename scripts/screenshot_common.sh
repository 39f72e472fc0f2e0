# Sourced (not run) by scripts/screenshot_report.sh and
# scripts/screenshot_replay.sh: the parts both headless-Chromium checks share.
#   screenshot_usage "$@"         exit 2 with the usage unless 1 or 2 args
#   find_chromium NAME            browser=<path of chromium>; if there is none,
#                                 "NAME: chromium not installed, skipping" and
#                                 exit 77 (ctest's skip code)
#   make_fixture_report ROOT DIR  a synthetic results DIR
#                                 (reports/make_fixture.py) and its report
#   page_path NAME FILE HINT      prints FILE's absolute path; if it does not
#                                 exist, "NAME: FILE not found (HINT)" and
#                                 exit 2 (use as x=$(page_path ...))

screenshot_usage() {
  if [ $# -lt 1 ] || [ $# -gt 2 ]; then
    echo "usage: $0 DIR [OUT.png]" >&2
    exit 2
  fi
}

find_chromium() {
  browser=""
  for candidate in chromium chromium-browser; do
    if command -v "$candidate" > /dev/null 2>&1; then
      browser=$(command -v "$candidate")
      return 0
    fi
  done
  echo "$1: chromium not installed, skipping" >&2
  exit 77
}

make_fixture_report() {
  /usr/bin/python3 "$1/reports/make_fixture.py" "$2" > /dev/null
  /usr/bin/python3 "$1/reports/make_report.py" "$2" > /dev/null
}

page_path() {
  if [ ! -f "$2" ]; then
    echo "$1: $2 not found ($3)" >&2
    exit 2
  fi
  echo "$(cd "$(dirname "$2")" && pwd)/$(basename "$2")"
}
