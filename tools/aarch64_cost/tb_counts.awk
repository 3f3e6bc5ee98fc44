# From qemu-user's "-d in_asm,exec,nochain" log: every translated block once per owner, with how
# often it ran for that owner, its symbol and its instruction words, one line each:
# "<owner> <count> <symbol> <word> <word> ...". With -v entries="symbol=owner ...", a block of an
# entry symbol (a module's step function) makes its owner the current one, and every block run
# until the next entry is charged to it: shared helpers go to the module that called them, which
# holds while the modules run one after another on one thread (synchronous replay). Without
# entries, every block's owner is "-".
BEGIN {
  owner = "-"
  n_entries = split(entries, pairs, " ")
  for (i = 1; i <= n_entries; i++) { split(pairs[i], kv, "="); owner_of[kv[1]] = kv[2] }
}
/^IN: / { sym = substr($0, 5); pc = ""; next }
/^0x[0-9a-f]+:/ {
  if (pc == "") {
    pc = substr($1, 3, length($1) - 3); sub(/^0+/, "", pc)
    words[pc] = ""; name[pc] = sym
    if (sym in owner_of) enters[pc] = owner_of[sym]
  }
  words[pc] = words[pc] " " $2
  next
}
/^$/ { pc = ""; next }
/^Trace / {
  split($0, f, "/")
  p = f[2]; sub(/^0+/, "", p)
  if (p in enters) owner = enters[p]
  n[owner, p]++
}
END {
  for (key in n) {
    split(key, k, SUBSEP)
    if (k[2] in words) printf "%s %d %s%s\n", k[1], n[key], name[k[2]], words[k[2]]
  }
}
