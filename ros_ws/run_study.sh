#!/usr/bin/env bash
# The paper's comparison through the node graph: 5 learners x 10 seeds x 5000 movements,
# several runs side by side, resumable (finished runs are skipped). --help for the options.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck disable=SC1091
source "$here/env.sh"
export SGIM_ENV_SOURCED=1
exec python -m sgim_nodes.graph.batch "$@"
