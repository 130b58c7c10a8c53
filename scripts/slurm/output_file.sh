# write_output PATH: writes standard input to PATH the way range_nlm's programs write every
# output (src/io/output_file.h). Sourced by submit.sh.
#  - a new or regular file: written to .NAME.tmpPID beside it, flushed to disk, then renamed over
#    NAME, so that no half-written file ever carries the name; on failure it is removed;
#  - a symbolic link (a chain, relative, dangling): followed, its final target written as above;
#    the link stays a link;
#  - a character device or a FIFO: written in place (no temporary file, no rename);
#  - a directory, block device, socket, or a path ending in '/': refused, saying what it is.
# Returns 1 with a message naming PATH if it cannot write.
write_output() {
  local path=$1 target kind temporary
  if [[ $path == */ ]]; then
    echo "'$path': ends with '/', so it names a directory; refusing to write there (give a file name)" >&2
    return 1
  fi
  target=$(readlink -m -- "$path") || { echo "'$path': cannot resolve the output path" >&2; return 1; }
  if [[ -c $target || -p $target ]]; then
    cat >"$target" || { echo "'$path': cannot write the output" >&2; return 1; }
    return 0
  fi
  if [[ -e $target && ! -f $target ]]; then
    kind="not a regular file, character device or FIFO"
    [[ -d $target ]] && kind="a directory"
    [[ -b $target ]] && kind="a block device"
    [[ -S $target ]] && kind="a socket"
    echo "'$path': is $kind; refusing to write over it (give a regular file, a character device such as /dev/null, or a FIFO)" >&2
    return 1
  fi
  temporary="$(dirname -- "$target")/.$(basename -- "$target").tmp$$"
  if ! { cat >"$temporary" && sync -- "$temporary" && mv -f -- "$temporary" "$target"; }; then
    rm -f -- "$temporary"
    echo "'$path': cannot write the output file; nothing was written under this name" >&2
    return 1
  fi
}
