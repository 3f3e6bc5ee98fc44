# From qemu-user's "-d in_asm,exec,nochain" log: every translated block once, with how often it
# ran, its symbol and its instruction words, one line each: "<count> <symbol> <word> <word> ...".
/^IN: / { sym = substr($0, 5); pc = ""; next }
/^0x[0-9a-f]+:/ {
  if (pc == "") {
    pc = substr($1, 3, length($1) - 3); sub(/^0+/, "", pc)
    words[pc] = ""; name[pc] = sym
  }
  words[pc] = words[pc] " " $2
  next
}
/^$/ { pc = ""; next }
/^Trace / {
  split($0, f, "/")
  p = f[2]; sub(/^0+/, "", p)
  n[p]++
}
END { for (p in n) if (p in words) printf "%d %s%s\n", n[p], name[p], words[p] }
