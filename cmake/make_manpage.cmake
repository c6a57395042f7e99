# cmake -DEXE=path/to/organsim -DOUTPUT=organsim.1.gz -P make_manpage.cmake
# Writes the man page from the command's own help: `organsim --help`, then
# `organsim <command> --help` for every command it lists, so the page says
# what the binary it ships with accepts. gzip -9n (no name or time stamp in
# the header) keeps the package's bytes the same from build to build.
function(run_help out)
  execute_process(COMMAND ${EXE} ${ARGN} OUTPUT_VARIABLE text RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "`organsim ${ARGN}` failed (${rc}): ${err}")
  endif()
  # CLI11 names the program as it was started: the build tree's path.
  string(REPLACE "${EXE}" "organsim" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# roff: a backslash is \e, and a line starting with . or ' is a request.
function(roff_escape out text)
  string(REPLACE "\\" "\\e" text "${text}")
  string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

run_help(version --version)
string(STRIP "${version}" version)
run_help(help --help)

# The command names: the lines under "Subcommands:" ("  name   description").
string(REGEX MATCH "Subcommands:\n.*" commands_block "${help}")
string(REPLACE "\n" ";" lines "${commands_block}")
set(commands "")
foreach(line IN LISTS lines)
  if(line MATCHES "^  ([a-z][a-z0-9_-]*)  ")
    list(APPEND commands ${CMAKE_MATCH_1})
  endif()
endforeach()
if(NOT commands)
  message(FATAL_ERROR "no commands found in `organsim --help`:\n${help}")
endif()

# The first help line is "organsim <version>: <summary>".
string(REGEX MATCH "^[^\n]*" first_line "${help}")
string(REGEX REPLACE "^organsim [^:]*: *" "" summary "${first_line}")
string(REGEX REPLACE "\\.$" "" summary "${summary}")
roff_escape(summary "${summary}")
roff_escape(help_roff "${help}")

set(page ".TH ORGANSIM 1 \"\" \"${version}\" \"User Commands\"\n")
string(APPEND page ".SH NAME\norgansim \\- ${summary}\n")
string(APPEND page ".SH SYNOPSIS\n.B organsim\n.I command\n[\\fIoptions\\fR]\n")
string(APPEND page ".SH DESCRIPTION\n.nf\n${help_roff}.fi\n")
string(APPEND page ".SH COMMANDS\n")
foreach(command IN LISTS commands)
  run_help(command_help ${command} --help)
  roff_escape(command_help "${command_help}")
  string(APPEND page ".SS ${command}\n.nf\n${command_help}.fi\n")
endforeach()
string(APPEND page ".SH FILES\n")
string(APPEND page "Scenarios, example surfaces and meshes: \\fIshare/organsim/\\fR under the install prefix, \\fI/usr\\fR for the Debian package (run them from there, e.g. \\fBorgansim run /usr/share/organsim/scenarios/default.json\\fR; a scenario's relative paths resolve against its own folder, and the outputs go to \\fIout/<scenario name>/\\fR in the working folder).\n")
string(APPEND page "Documentation: \\fIshare/doc/organsim/\\fR under the install prefix.\n")
string(APPEND page ".SH VERSION\n${version}\n")

get_filename_component(dir ${OUTPUT} DIRECTORY)
file(WRITE ${dir}/organsim.1 "${page}")
find_program(GZIP_EXECUTABLE gzip REQUIRED)
execute_process(COMMAND ${GZIP_EXECUTABLE} -9nc INPUT_FILE ${dir}/organsim.1 OUTPUT_FILE ${OUTPUT}.tmp RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "gzip failed (${rc})")
endif()
file(RENAME ${OUTPUT}.tmp ${OUTPUT})
