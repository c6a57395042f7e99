#include "core/sweep/slurm_script.h"

#include <sstream>

namespace organsim {

int slurm_array_tasks(size_t ncases, const SlurmOptions& o) {
  const size_t per = static_cast<size_t>(o.cases_per_task < 1 ? 1 : o.cases_per_task);
  return static_cast<int>((ncases + per - 1) / per);
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string slurm_script(const SlurmOptions& o, size_t ncases, const std::filesystem::path& organsim,
                         const std::filesystem::path& sweep_file, const std::filesystem::path& outdir) {
  const int tasks = slurm_array_tasks(ncases, o);
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# organsim sweep as a Slurm job array: " << ncases << " cases in " << tasks << " tasks of at most "
    << o.cases_per_task << " (task i runs cases i, i+" << tasks << ", ...).\n"
    << "# Submit: sbatch " << (outdir / "sweep.sbatch").string() << "\n"
    << "# Afterwards: organsim sweep --collect " << outdir.string() << "\n"
    << "#SBATCH --job-name=" << o.job_name << "\n"
    << "#SBATCH --array=0-" << tasks - 1
    << (o.max_parallel > 0 ? std::string("%").append(std::to_string(o.max_parallel)) : "") << "\n"
    << "#SBATCH --ntasks=1\n"
    << "#SBATCH --cpus-per-task=" << o.cpus_per_task << "\n"
    << "#SBATCH --time=" << o.time << "\n";
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
  s << "#SBATCH --output=" << (outdir / "slurm" / "%A_%a.out").string() << "\n"
    << "set -euo pipefail\n";
  for (const std::string& line : o.setup) s << line << "\n";
  s << "exec " << shell_quote(organsim.string()) << " sweep " << shell_quote(sweep_file.string()) << " -o "
    << shell_quote(outdir.string()) << " --shard slurm --jobs " << o.cpus_per_task
    << (o.retry_failed ? " --retry-failed" : "") << "\n";
  return s.str();
}

}  // namespace organsim
