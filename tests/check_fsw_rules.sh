#!/usr/bin/env bash
# fsw/ must stay exception-free, heap-free and I/O-free: fail on any forbidden construct.
set -u
dir=${1:?usage: check_fsw_rules.sh FSW_DIR}
pattern='\bthrow\b|\btry[[:space:]]*\{|\bcatch[[:space:]]*\(|\bnew[[:space:]]+[A-Za-z_]|\bdelete[[:space:]]|\b(malloc|calloc|realloc|free|alloca)[[:space:]]*\(|std::(vector|string|map|unordered_map|list|deque|function|shared_ptr|unique_ptr|make_shared|make_unique|cout|cerr)|#include[[:space:]]*<(iostream|fstream|sstream|string|vector|map|thread|mutex|chrono|cstdio|functional)>|\b(printf|fprintf|puts|fopen)[[:space:]]*\(|dynamic_cast|typeid|Eigen::Dynamic|MatrixXd|VectorXd'
hits=$(grep -rnE "$pattern" "$dir" --include='*.hpp' --include='*.cpp' --include='*.h' | grep -v '// fsw-rules: allowed')
if [ -n "$hits" ]; then
  echo "fsw/ coding rule violations:"
  echo "$hits"
  exit 1
fi
echo "fsw coding rules: $(find "$dir" -name '*.[ch]pp' | wc -l) files clean"
