# pepper_target_defaults(<target> [CXX_STANDARD <n>]): warnings (errors with PEPPER_WERROR) and
# sanitizers for our own code only. Our code is C++20; CXX_STANDARD 17 is for the one target that
# includes ViSP 3.5 (visp_adapter/CMakeLists.txt says why).
function(pepper_target_defaults target)
  cmake_parse_arguments(PARSE_ARGV 1 _arg "" "CXX_STANDARD" "")
  if(NOT _arg_CXX_STANDARD)
    set(_arg_CXX_STANDARD 20)
  endif()
  target_compile_features(${target} PUBLIC cxx_std_${_arg_CXX_STANDARD})
  set_target_properties(${target} PROPERTIES CXX_STANDARD ${_arg_CXX_STANDARD}
                                             CXX_STANDARD_REQUIRED ON CXX_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
  if(PEPPER_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(PEPPER_SANITIZERS)
    list(JOIN PEPPER_SANITIZERS "," _san)
    target_compile_options(${target} PRIVATE -fsanitize=${_san} -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=${_san})
  endif()
endfunction()
