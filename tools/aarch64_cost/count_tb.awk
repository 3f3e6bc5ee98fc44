# Counts guest instructions from qemu-user's "-d in_asm,exec,nochain" log: in_asm gives each
# translated block's instructions (under "IN: <symbol>"), exec one line per executed block.
# Prints instructions executed per symbol, then the total.
/^IN: / { sym = substr($0, 5); pc = ""; next }
/^0x[0-9a-f]+:/ {
  if (pc == "") {
    pc = substr($1, 3, length($1) - 3); sub(/^0+/, "", pc)
    size[pc] = 0; name[pc] = sym
  }
  size[pc]++
  next
}
/^$/ { pc = ""; next }
/^Trace / {
  split($0, f, "/")
  p = f[2]; sub(/^0+/, "", p)
  n[name[p]] += size[p]
  total += size[p]
}
END {
  for (s in n) printf "%14.0f %s\n", n[s], s
  printf "%14.0f TOTAL\n", total
}
