#pragma once
// The firmware's bus: every message that passes between rows, declared once. The rows' factories
// (firmware/rows.hpp) take what each row reads and writes from here through a Wiring, which
// notes it; `sen3bot graph` prints the flow that results and docs/architecture.md quotes it.
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

struct Topics {
  // What the devices measured, as the drivers' adapters turn it into messages.
  tasks::Topic<msg::ScanMessage> scan{"scan"};
  tasks::Topic<msg::Odometry> odometry{"odometry"};
  tasks::Topic<msg::BaseFlags> base_flags{"base_flags"};
  tasks::Topic<msg::Sonar> sonar{"sonar"};
  tasks::Topic<msg::PersonDetections> detections{"detections"};
  tasks::Topic<msg::SafetyIo> safety_io{"safety_io"};
  tasks::Topic<msg::TagFrame> tags{"tags"};

  // Where the robot is and where it is going.
  tasks::Topic<msg::PoseEstimate> pose{"pose"};
  tasks::Topic<msg::NavGoal> goal{"goal"};
  // The mission's or the fleet's goals when the collaborative mode passes them on as `goal`.
  tasks::Topic<msg::NavGoal> cooperative_goal{"cooperative_goal"};
  tasks::Topic<msg::PathMessage> path{"path"};
  tasks::Topic<msg::FormationCommand> formation{"formation"};

  // Who and what moves around it.
  tasks::Topic<msg::MovingObstacles> movers{"movers"};
  tasks::Topic<msg::People> people{"people"};

  // Motion: the local planner's request, the safety filter's answer that the base drives.
  tasks::Topic<msg::VelocityCommand> request{"request"};
  tasks::Topic<msg::VelocityCommand> command{"command"};
  tasks::Topic<msg::ControllerStatus> controller_status{"controller_status"};
  tasks::Topic<msg::SafetyOutput> safety_output{"safety_output"};
  tasks::Topic<msg::OperatingMode> operating_mode{"operating_mode"};

  // The collaborative mode.
  tasks::Topic<msg::CobotState> cobot_state{"cobot_state"};
  tasks::Topic<msg::WorkerPath> worker_path{"worker_path"};
  tasks::Topic<msg::OperationEstimate> operation{"operation"};
  tasks::Topic<msg::PathMessage> operation_reference{"operation_reference"};

  // For the live view: the local costmap, every few controller cycles.
  tasks::Topic<msg::CostmapSnapshot> local_costmap{"local_costmap"};
};

}  // namespace sen3bot::firmware
