#!/usr/bin/env bash
# Local S3 server for tests: `moto.sh start STATE PORT BUCKET` installs moto[server] into a venv
# under STATE when absent, starts moto_server on 127.0.0.1:PORT, creates a user with an access
# key and BUCKET, and writes STATE/env (`export AWS_...` lines to source); `moto.sh stop STATE`
# stops that server by its PID. moto's optional IAM check (INITIAL_NO_AUTH_ACTION_COUNT) reads
# only the Authorization header, not presigned (query-string) signatures as groove sends, so it
# stays off: moto accepts any credentials.
set -euo pipefail
cmd=${1:?usage: moto.sh start STATE PORT BUCKET | stop STATE}
state=$(mkdir -p "${2:?state folder}" && cd "$2" && pwd)
case $cmd in
start)
  port=${3:?port}; bucket=${4:?bucket}
  if [ ! -x "$state/venv/bin/moto_server" ]; then
    if ! python3 -m venv "$state/venv" 2>/dev/null; then
      # Debian's python3 keeps venv (ensurepip) in a package of its own
      rm -rf "$state/venv"
      export DEBIAN_FRONTEND=noninteractive
      apt-get update -qq && apt-get install -y -qq python3-venv >/dev/null
      python3 -m venv "$state/venv"
    fi
    "$state/venv/bin/pip" install -q "moto[server]"
  fi
  "$state/venv/bin/moto_server" -H 127.0.0.1 -p "$port" >"$state/moto.log" 2>&1 &
  echo $! > "$state/moto.pid"
  for _ in $(seq 100); do
    if "$state/venv/bin/python" - "$port" "$bucket" "$state/env" <<'PY' 2>/dev/null
import json, sys, urllib.request, boto3
url = f"http://127.0.0.1:{sys.argv[1]}"
urllib.request.urlopen(url + "/moto-api/", timeout=1)  # up yet? (does not count as an action)
kw = dict(endpoint_url=url, region_name="us-east-1")
iam = boto3.client("iam", aws_access_key_id="bootstrap", aws_secret_access_key="bootstrap", **kw)
iam.create_user(UserName="groove-ci")
key = iam.create_access_key(UserName="groove-ci")["AccessKey"]
iam.put_user_policy(UserName="groove-ci", PolicyName="s3", PolicyDocument=json.dumps(
    {"Version": "2012-10-17", "Statement": [{"Effect": "Allow", "Action": "s3:*", "Resource": "*"}]}))
boto3.client("s3", aws_access_key_id=key["AccessKeyId"], aws_secret_access_key=key["SecretAccessKey"],
             **kw).create_bucket(Bucket=sys.argv[2])
with open(sys.argv[3], "w") as f:
    f.write(f"export AWS_ACCESS_KEY_ID={key['AccessKeyId']}\n")
    f.write(f"export AWS_SECRET_ACCESS_KEY={key['SecretAccessKey']}\n")
    f.write(f"export AWS_ENDPOINT_URL={url}\nexport AWS_REGION=us-east-1\n")
PY
    then echo "moto: up on 127.0.0.1:$port, bucket $bucket, credentials in $state/env"; exit 0; fi
    sleep 0.2
  done
  echo "moto: did not start; see $state/moto.log" >&2
  exit 1
  ;;
stop)
  if [ -s "$state/moto.pid" ]; then
    pid=$(cat "$state/moto.pid")
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
    rm -f "$state/moto.pid"
  fi
  echo "moto: stopped"
  ;;
*) echo "usage: moto.sh start STATE PORT BUCKET | stop STATE" >&2; exit 2 ;;
esac
