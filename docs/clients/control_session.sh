#!/usr/bin/env bash
# A control session with liblo's oscsend (apt-get install liblo-tools) against a running
# `emoshift serve --control 127.0.0.1:9001`. Replies (<address>/confirm or /emoshift/error)
# go back to the sender's address; watch them with `oscdump 9200` and add `-p 9200`... or
# simply run the commands and check the daemon's log. It holds no subscription, so it has no
# lease to renew (docs/clients/receive_marker.py shows a subscriber that renews). The recording
# goes to $OUT (default /tmp); existing files there are refused, not overwritten.
set -eu
D=${DAEMON_HOST:-127.0.0.1}
P=${DAEMON_PORT:-9001}
OUT=${OUT:-/tmp}

oscsend "$D" "$P" /status                       # counters come back as /status/confirm
oscsend "$D" "$P" /emotion/ramp f 0.5           # glide 0.5 s between settings
oscsend "$D" "$P" /emotion/target s happy       # move towards the learned "happy" level
oscsend "$D" "$P" /emotion/amount f 0.75        # three quarters of the way
sleep 2
oscsend "$D" "$P" /emotion/target s frustrated
oscsend "$D" "$P" /emotion/amount f 1.0
sleep 2
oscsend "$D" "$P" /emotion/alpha if 2 0.5       # raw translate of component 2
oscsend "$D" "$P" /component/gain if 1 1.2      # exaggerate component 1
oscsend "$D" "$P" /bypass i 1                   # pass frames through unedited
oscsend "$D" "$P" /bypass i 0
oscsend "$D" "$P" /record/start ss "$OUT/edited.c3d" "$OUT/input.c3d"   # edited + raw input
sleep 2
oscsend "$D" "$P" /record/stop
oscsend "$D" "$P" /model/load s model.json      # hot reload; a bad file keeps the old model
