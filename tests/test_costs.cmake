# Included by CTest after the GoogleTest cases of tests/ are registered: the cases that
# take longest get a COST, so that a parallel run (ctest -j) starts them first instead of
# ending on one of them alone. CTest orders by the times it measured once it has any (its
# Testing/Temporary/CTestCostData.txt); these hints serve a build folder's first run, which
# is every run of ./skyloc.sh test from a fresh clone. Seconds, measured under qemu-arm
# (the slowest build) on 2026-11-28; a name a build does not have is ignored.
set_tests_properties(Demo.QuickRunWritesOnlyItsRouteAndLeavesNothing PROPERTIES COST 53)
set_tests_properties(Surf1dSimTest.PlacesAlongTheRouteAreRecognised PROPERTIES COST 52)
set_tests_properties(FrameLoop.ThousandsOfRepeatFramesAllocateNothing PROPERTIES COST 40)
set_tests_properties(SkyDescriptor.OversampledGridMovesLessWithAYawThanTheMinimalGrid
                     PROPERTIES COST 23)
set_tests_properties(Surf1dSimTest.RecoversTheRobotsTurnAtOnePlace PROPERTIES COST 19)
set_tests_properties(FrameLoop.AttitudeOnAllocatesNothingAndADeadImuLeavesFramesLevel
                     PROPERTIES COST 17)
set_tests_properties(FisheyeStrips.SurfRecoversTheYawOfTheScene
                     FisheyeStrips.StripCorrelationRecoversTheSameYaw
                     Surf1dTest.MatchedPlacesOutscoreUnrelatedOnes PROPERTIES COST 11)
set_tests_properties(World.ProceduralWorldsAreDeterministicAndHaveRoutes
                     ZenithEstimate.SkylinePlaneFindsTheTiltOfAnOpenHorizon PROPERTIES COST 8)
