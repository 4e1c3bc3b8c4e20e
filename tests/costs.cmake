# The seconds the slowest of the main tests take under ctest -j2 on 2 cores (their COST), read by
# ctest after the discovered tests: a first run, which has no timings of its own yet, starts them
# first, and the short tests fill the cores around them instead of one long test ending the run
# alone. A name that no longer matches a test stops ctest, naming it here.
foreach(test_and_cost IN ITEMS
    "Each scene's render agrees with its reference within both images' noise, region by region|100"
    "A closed box lit only from outside is black inside, with every method|60"
    "lucent compare --test: a path-traced candidate passes its reference, scaled by 1.01 it fails|42"
    "A render split by crops and sample ranges merges into the single render, bit for bit|39"
    "A render killed after a checkpoint resumes to the uninterrupted image, bit for bit|30"
    "Every method's options reach the command line, the help, the JSON line and the EXR|35"
    "Closed furnace: one bounce gives Le (1 + rho + rho^2), multiple bounces Le / (1 - rho)|29"
    "A rough glTF volume on a floor: purcell and pmfg render the light it refracts as the path tracer does|25"
    "Mappings: the weights of a uniform unit radiance sum to the directional albedo|22"
    "Cornell box: micro with direct-lit points agrees with the path tracer at max depth 2|19"
    "SIGINT and SIGTERM stop a render with a checkpoint and an image marked partial|18"
    "loader: lucent render rejects every broken scene: message, non-zero status, no files|18"
    "Runs: a 2% bias in one region of sixteen is found, a bias beyond the margin is not passed|18")
  string(FIND "${test_and_cost}" "|" bar REVERSE)
  string(SUBSTRING "${test_and_cost}" 0 ${bar} name)
  math(EXPR after "${bar} + 1")
  string(SUBSTRING "${test_and_cost}" ${after} -1 cost)
  set_tests_properties("${name}" PROPERTIES COST ${cost})
endforeach()
