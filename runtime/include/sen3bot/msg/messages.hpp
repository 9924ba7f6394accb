#pragma once
// The bus vocabulary: every message a Topic carries between drivers, navigation and the
// mission. Fixed-size and trivially copyable; nothing here depends on an algorithm or driver.
//
//   message           header          published by                     consumed by
//   ScanMessage       laser.hpp       bridge (from the LMS200 driver)  localization, controller, safety
//   Odometry          base.hpp        bridge (from the P2OS driver)    localization, controller, safety
//   BaseFlags         base.hpp        bridge (e-stop, motors)          safety
//   PoseEstimate      navigation.hpp  localization                     planner, controller, safety, mission
//   NavGoal           navigation.hpp  mission / command line           planner
//   PathMessage       navigation.hpp  planner                          controller, mission
//   ControllerStatus  navigation.hpp  controller                       mission, telemetry
//   VelocityCommand   navigation.hpp  controller (requested)           safety
//                                     safety (to the base)             bridge (to the P2OS driver)
//   SafetyOutput      navigation.hpp  safety (command and reasons)     mission, telemetry
//   PersonDetections  people.hpp      a person detector (boxes)        people fusion
//   People            people.hpp      people fusion (tracks, cages)    planner, controller
//   SafetyIo          io.hpp          CAN I/O (e-stop chain, bumpers)  safety
//   OperatingMode     io.hpp          collaborative mode (wait4col)    CAN I/O (status light)
//   TagFrame          cobot.hpp       QR reader (camera frames)        collaborative mode
//   CobotState        cobot.hpp       collaborative mode               people (operator's cage), mission
//   WorkerPath        cobot.hpp       collaborative mode (recorder)    operation recognition
//   OperationEstimate cobot.hpp       operation recognition            collaborative mode, telemetry
#include "sen3bot/msg/base.hpp"
#include "sen3bot/msg/cobot.hpp"
#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/msg/io.hpp"
#include "sen3bot/msg/laser.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/msg/people.hpp"
