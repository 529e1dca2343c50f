#!/usr/bin/env bash
# Make sure FFmpeg (ffmpeg and ffprobe) is on PATH: the toolkit decodes
# video files and cameras with it. Installs Debian's package when missing.
set -euo pipefail
if command -v ffmpeg >/dev/null && command -v ffprobe >/dev/null; then
    exit 0
fi
if ! command -v apt-get >/dev/null; then
    echo "FFmpeg is missing and this is not a Debian-like system: install ffmpeg with your package manager" >&2
    exit 1
fi
sudo=()
if [ "$(id -u)" != 0 ]; then
    sudo=(sudo)
fi
echo "installing FFmpeg from the distribution's packages" >&2
"${sudo[@]}" apt-get update -qq >&2
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends ffmpeg >&2
