# Sourced by the scripts that start `organsim serve --port 0` in the
# background: serve_port OUT_FILE PID TENTHS prints the port the server
# announced on OUT_FILE ("OpenIGTLink on ADDRESS:PORT"), waiting up to TENTHS
# tenths of a second while PID lives; it prints nothing if none came.
serve_port() {
  local out=$1 pid=$2 tenths=$3 port=
  for _ in $(seq 1 "$tenths"); do
    port=$(sed -n 's/.*OpenIGTLink on [0-9.]*:\([0-9]*\).*/\1/p' "$out")
    [ -n "$port" ] && break
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  echo "$port"
}
