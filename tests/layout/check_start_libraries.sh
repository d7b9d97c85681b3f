#!/usr/bin/env bash
# The programs named must start without OpenCV's image codecs and capture, and what they bring (GDAL,
# GStreamer, FFmpeg: about 240 shared libraries, 0.4 s of every start): rhot calls those through
# tracking/media/Media.h, whose module is opened on first use. A program that maps one of them at
# start (ldd) fails the check, named with what it maps.
set -euo pipefail
status=0
for program in "$@"; do
  if ! libraries=$(ldd "${program}" 2>&1); then
    echo "${program}: ldd cannot read it: ${libraries}"
    status=1
    continue
  fi
  heavy=$(grep -oE 'lib(opencv_imgcodecs|opencv_videoio|gdal|gstreamer-1\.0|avcodec)[^ ]*' <<<"${libraries}" | sort -u | tr '\n' ' ' || true)
  if [[ -n "${heavy}" ]]; then
    echo "${program} maps at start: ${heavy}(call them through tracking/media/Media.h)"
    status=1
  fi
done
if [[ ${status} -eq 0 ]]; then
  echo "check_start_libraries: $# programs start without OpenCV's image codecs and capture"
fi
exit ${status}
