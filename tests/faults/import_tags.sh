#!/usr/bin/env bash
# The recording importer never guesses a time base: a missing, cut or inconsistent .tag, or a
# truncated IMU CSV, is an error naming the file; --imu-clock-ratio is the documented fallback to
# the IMU's own clock (with a warning). One bad tick line costs that line only. Needs the drive
# data set (skips with exit 77 when absent).
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib.sh"
src="$data/gnss-imu-drive"
[ -f "$src/imu_1934.csv.tag" ] || { echo "SKIP: the drive data set is not in $data"; exit 77; }
d="$out/drive"
mkdir -p "$d"
cp "$src/imu_1934.csv" "$src/imu_1934.csv.tag" "$src/gnss_1934_sf.pos" "$d/"
csv_sum=$(sum "$d/imu_1934.csv"); tag_sum=$(sum "$d/imu_1934.csv.tag")
lines=$(wc -l < "$d/imu_1934.csv")

run 0 good -- "$sdins" import rtklib "$d" --log "$out/good.lcmlog" --json "$out/good.json"
imu_ok=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["imu"]["lines"]["accepted"])' "$out/good.json")

# one tick 1e6 ms ahead in the middle: that line only is rejected
cp -r "$d" "$out/jump"
awk -F, -v n=$((lines / 2)) 'NR==n {$7=$7+1000000} {print}' OFS=, "$d/imu_1934.csv" > "$out/jump/imu_1934.csv"
run 0 tick_jump -- "$sdins" import rtklib "$out/jump" --log "$out/jump.lcmlog" --json "$out/jump.json"
imu_jump=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["imu"]["lines"]["accepted"])' "$out/jump.json")
[ "$imu_jump" = $((imu_ok - 1)) ] || fail "tick jump: $imu_jump IMU lines accepted, expected $((imu_ok - 1))"

# truncated IMU CSV (half of it): the tag spans twice the IMU ticks
mkdir -p "$out/short_csv"; cp "$d/imu_1934.csv.tag" "$d/gnss_1934_sf.pos" "$out/short_csv/"
head -n $((lines / 2)) "$d/imu_1934.csv" > "$out/short_csv/imu_1934.csv"
run 1 short_csv -- "$sdins" import rtklib "$out/short_csv" --log "$out/short_csv.lcmlog"
says short_csv "imu_1934.csv.tag"; says short_csv "a cut .tag or a truncated IMU CSV"
absent "$out/short_csv.lcmlog"
# the documented fallback: the IMU's own clock, with a warning
run 0 short_csv_fallback -- "$sdins" import rtklib "$out/short_csv" --log "$out/short_fb.lcmlog" --imu-clock-ratio 1
says short_csv_fallback "warning"

# cut .tag (a tenth of its records)
mkdir -p "$out/cut_tag"; cp "$d/imu_1934.csv" "$d/gnss_1934_sf.pos" "$out/cut_tag/"
tag_bytes=$(stat -c %s "$d/imu_1934.csv.tag")
head -c $((76 + (tag_bytes - 76) / 80 * 8)) "$d/imu_1934.csv.tag" > "$out/cut_tag/imu_1934.csv.tag"
run 1 cut_tag -- "$sdins" import rtklib "$out/cut_tag" --log "$out/cut_tag.lcmlog"
says cut_tag "imu_1934.csv.tag"
absent "$out/cut_tag.lcmlog"
# header-only and too-short .tag
head -c 76 "$d/imu_1934.csv.tag" > "$out/cut_tag/imu_1934.csv.tag"
run 1 empty_tag -- "$sdins" import rtklib "$out/cut_tag" --log "$out/cut_tag.lcmlog"
says empty_tag "imu_1934.csv.tag"
head -c 30 "$d/imu_1934.csv.tag" > "$out/cut_tag/imu_1934.csv.tag"
run 1 short_tag -- "$sdins" import rtklib "$out/cut_tag" --log "$out/cut_tag.lcmlog"
says short_tag "imu_1934.csv.tag"
# missing .tag: an error, not a log without the IMU
rm "$out/cut_tag/imu_1934.csv.tag"
run 1 missing_tag -- "$sdins" import rtklib "$out/cut_tag" --log "$out/cut_tag.lcmlog"
says missing_tag "imu_1934.csv"; says missing_tag "time-tag file"
absent "$out/cut_tag.lcmlog"

unchanged "$d/imu_1934.csv" "$csv_sum"; unchanged "$d/imu_1934.csv.tag" "$tag_sum"
no_temporaries "$out"
done_ok
