# The options every script filling the virtual ARM board's cache takes,
# sourced by them: --cache DIR (default: $FPP_VM_CACHE or /var/cache/fpp-vm),
# --force, -h/--help (the script's opening comment). Sets `cache` and `force`.
# Usage: parse_cache_options NAME "$@"   (NAME: the script's, for errors)
parse_cache_options() {
  local name=$1
  shift
  cache="${FPP_VM_CACHE:-/var/cache/fpp-vm}"
  force=0
  while [ $# -gt 0 ]; do
    case "$1" in
      --cache) cache="$2"; shift 2 ;;
      --force) force=1; shift ;;
      -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
      *) echo "$name: unknown argument '$1'" >&2; exit 2 ;;
    esac
  done
}
