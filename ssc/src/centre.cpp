#include "sen3bot/ssc/centre.hpp"

#include <algorithm>
#include <new>

namespace sen3bot::ssc {

std::string_view to_string(CommandKind kind) noexcept {
  switch (kind) {
    case CommandKind::send: return "send";
    case CommandKind::suspend: return "suspend";
    case CommandKind::resume: return "resume";
  }
  return "?";
}

std::string_view to_string(Advice advice) noexcept {
  switch (advice) {
    case Advice::clear: return "CLEAR";
    case Advice::slow: return "SLOW";
    case Advice::stop: return "STOP";
  }
  return "?";
}

std::string_view to_string(EventType type) noexcept {
  switch (type) {
    case EventType::allocation: return "allocation";
    case EventType::coalition: return "coalition";
    case EventType::release: return "release";
    case EventType::advisory: return "advisory";
    case EventType::suspension: return "suspension";
    case EventType::resumption: return "resumption";
    case EventType::charge: return "charge";
    case EventType::home: return "home";
    case EventType::swap: return "swap";
    case EventType::task: return "task";
    case EventType::connection: return "connection";
  }
  return "?";
}

Result<std::unique_ptr<Centre>> Centre::create(const Site& site, const CentreConfig& config) {
  if (Status valid = site.validate(); !valid) return valid.error();
  if (config.stop_distance < 0 || config.slow_distance < config.stop_distance)
    return Error(Errc::config, "slow distance must be at least the stop distance, both non-negative");
  if (config.slow_speed_factor < 0 || config.slow_speed_factor > 1)
    return Error(Errc::config, "slow speed factor must be in [0, 1]");
  if (config.standing.charged < config.standing.low_battery)
    return Error(Errc::config, "the charged level must be at least the low battery level");
  std::unique_ptr<Centre> centre(new (std::nothrow) Centre(site, config));
  if (!centre) return Error(Errc::capacity, "no memory for the centre");
  return centre;
}

Centre::Centre(const Site& site, const CentreConfig& config) : site_(site), config_(config), people_(config.people) {
  for (const RobotHome& home : site.robots) {
    RobotSlot r;
    r.id = home.robot;
    r.name = home.name;
    r.home = home.pose;
    r.overlooks = home.overlooks;
    r.last.pose = home.pose;
    (void)robots_.push_back(r);  // as many slots as the site can hold
  }
}

// --- inputs ------------------------------------------------------------------------------

Status Centre::update_robot(const RobotReport& report) {
  RobotSlot* r = robot(report.robot);
  if (r == nullptr) return Error::format(Errc::not_found, "robot %u is not in the site", report.robot);
  r->last = report;
  r->reported = true;
  return Status::success();
}

Status Centre::set_online(RobotId id, bool online, Nanos now) {
  RobotSlot* r = robot(id);
  if (r == nullptr) return Error::format(Errc::not_found, "robot %u is not in the site", id);
  if (r->online == online) return Status::success();
  r->online = online;
  if (inbox_.full()) {
    ++out_.dropped;
  } else {
    Event e;
    e.type = EventType::connection;
    e.time = now;
    (void)e.robots.push_back(id);
    e.reason.format("%s is %s", r->name.c_str(), online ? "online" : "offline");
    (void)inbox_.push_back(e);
  }
  return Status::success();
}

Status Centre::update_agv(const AgvReport& report) {
  if (report.agv == kNone) return Error(Errc::invalid_argument, "AGV without an id");
  AgvSlot* a = agv(report.agv);
  if (a == nullptr) {
    if (!agvs_.emplace_back()) return Error::format(Errc::capacity, "more than %zu AGVs", kMaxAgvs);
    a = &agvs_.back();
    a->id = report.agv;
  }
  a->name = report.name.empty() ? Name("agv") : report.name;
  a->pose = report.pose;
  a->path.clear();
  (void)a->path.push_back(position(report.pose));
  for (const Point& p : report.route) (void)a->path.push_back(p);  // room for the pose and every node
  return Status::success();
}

void Centre::remove_agv(AgvId id) {
  agvs_.remove_if([&](const AgvSlot& a) { return a.id == id; });
}

Result<TaskId> Centre::submit_amr_task(const AmrRequest& request, Nanos now) {
  if (request.priority < 1 || request.priority > kLowest)
    return Error::format(Errc::invalid_argument, "AMR work has priority 1 or 2, not %u", request.priority);
  if (pending_.full()) return Error(Errc::capacity, "too many AMR requests waiting");
  const TaskId id = next_task_id();
  (void)pending_.push_back({id, request});
  if (inbox_.full()) {
    ++out_.dropped;
  } else {
    Event e;
    e.type = EventType::task;
    e.time = now;
    e.task = id;
    e.reason.format("AMR request %u queued as task %u (p = %u)", request.request, id, request.priority);
    (void)inbox_.push_back(e);
  }
  return id;
}

// --- the step ----------------------------------------------------------------------------

const Decisions& Centre::step(Nanos now) {
  now_ = now;
  out_.time = now;
  out_.commands.clear();
  out_.advisories.clear();
  out_.events.clear();
  out_.dropped = 0;
  for (const Event& e : inbox_) (void)out_.events.push_back(e);  // the output holds more than the inbox
  inbox_.clear();

  people_.expire(now);
  drop_offline_members();
  progress_tasks();
  battery_rule();
  update_coalitions();
  staff_coalitions();
  assign_requests();
  idle_rule();
  advise();
  return out_;
}

void Centre::drop_offline_members() {
  for (Coalition& c : coalitions_) {
    for (std::size_t i = 0; i < c.members.size();) {
      RobotSlot* r = robot(c.members[i]);
      if (r->online) {
        ++i;
        continue;
      }
      Event& e = event(EventType::release, kNone, c.area);
      (void)e.robots.push_back(r->id);
      e.reason.format("%s went offline while monitoring %s; a free robot replaces it", r->name.c_str(), area_name(c.area));
      r->tasks.finish();  // its monitoring ends; suspended work waits until it is back
      c.members.erase(c.members.begin() + i);
    }
  }
}

void Centre::progress_tasks() {
  for (RobotSlot& r : robots_) {
    if (!r.online || !r.reported || !r.tasks.is(TaskKind::amr)) continue;
    const Task& t = *r.tasks.current();
    if (r.last.order_task != t.id || !r.last.order_finished || r.last.driving) continue;
    Event& e = event(EventType::task);
    (void)e.robots.push_back(r.id);
    e.task = t.id;
    e.reason.format("%s finished AMR task %u (request %u)", r.name.c_str(), t.id, t.request);
    r.tasks.finish();  // the idle rule resumes suspended work or sends it home
  }
}

void Centre::battery_rule() {
  for (RobotSlot& r : robots_) {
    if (!r.online || !r.reported) continue;
    const StandingAction action = standing_rule(r.tasks, r.last.battery, config_.standing);
    if (action == StandingAction::charged) {
      r.tasks.finish();
      if (!r.tasks.suspended().empty()) continue;  // the idle rule resumes it
      Task home{next_task_id(), TaskKind::home, kLowest, r.home, kNone, 0};
      (void)r.tasks.start(home);  // nothing current to suspend
      Event& e = event(EventType::home);
      (void)e.robots.push_back(r.id);
      e.task = home.id;
      e.reason.format("%s charged to %.0f %%: waits at home (p = 2)", r.name.c_str(), r.last.battery);
      continue;
    }
    if (action != StandingAction::charge) continue;
    if (Coalition* c = coalition_of(r.id)) {
      Event& e = event(EventType::release, kNone, c->area);
      (void)e.robots.push_back(r.id);
      e.reason.format("%s leaves %s to charge (battery %.0f %%)", r.name.c_str(), area_name(c->area), r.last.battery);
      remove_member(*c, r.id);
    }
    // Charging wins over monitoring (both p = 0): a robot with a flat battery monitors nothing.
    Task charge{next_task_id(), TaskKind::charge, kHighest, r.home, kNone, 0};
    Reason why;
    why.format("battery %.0f %% below %.0f %%%s", r.last.battery, config_.standing.low_battery,
               r.last.charging ? ", already charging" : "");
    if (!r.tasks.is(TaskKind::amr)) r.tasks.finish();  // home and monitoring end; AMR work is suspended
    take(r, charge, why.c_str(), /*send=*/!r.last.charging);
    Event& e = event(EventType::charge);
    (void)e.robots.push_back(r.id);
    e.task = charge.id;
    e.reason.format("%s: %s; to its charging station (p = 0)", r.name.c_str(), why.c_str());
  }
}

void Centre::update_coalitions() {
  for (AgvSlot& a : agvs_) a.crossings = crossings(site_, a.path.as_span());
  auto first_area = [](const AgvSlot& a) { return a.crossings.empty() ? kNone : a.crossings[0].area; };

  // Release coalitions no AGV needs first any more.
  for (std::size_t i = 0; i < coalitions_.size();) {
    Coalition& c = coalitions_[i];
    StaticVector<AgvId, kMaxAgvs> still;
    for (const AgvSlot& a : agvs_)
      if (first_area(a) == c.area) (void)still.push_back(a.id);
    for (const AgvId gone : c.agvs) {
      if (std::find(still.begin(), still.end(), gone) != still.end()) continue;
      const AgvSlot* a = agv(gone);
      const bool crossed = a != nullptr && std::any_of(a->crossings.begin(), a->crossings.end(),
                                                       [&](const Crossing& x) { return x.area == c.area; });
      Event& e = event(EventType::release, gone, c.area);
      if (a == nullptr)
        e.reason.format("AGV %u left; no longer served at %s", gone, area_name(c.area));
      else if (crossed)
        e.reason.format("%s now meets another area first; no longer served at %s", a->name.c_str(), area_name(c.area));
      else
        e.reason.format("%s has passed %s", a->name.c_str(), area_name(c.area));
    }
    c.agvs = still;
    if (!c.agvs.empty()) {
      ++i;
      continue;
    }
    Event& e = event(EventType::release, kNone, c.area);
    for (const RobotId m : c.members) (void)e.robots.push_back(m);
    e.reason.format("coalition at %s released: no AGV route crosses it first", area_name(c.area));
    const auto members = c.members;
    const AreaId area = c.area;
    coalitions_.erase(coalitions_.begin() + i);
    for (const RobotId m : members) {
      Reason why;
      why.format("released from %s", area_name(area));
      rest(*robot(m), why.c_str());
    }
  }

  // Start (or join) the coalition of each AGV's first crossed area.
  for (const AgvSlot& a : agvs_) {
    const AreaId area = first_area(a);
    if (area == kNone) continue;
    Coalition* c = nullptr;
    for (Coalition& existing : coalitions_)
      if (existing.area == area) c = &existing;
    if (c != nullptr) {
      if (std::find(c->agvs.begin(), c->agvs.end(), a.id) != c->agvs.end()) continue;
      (void)c->agvs.push_back(a.id);
      Event& e = event(EventType::coalition, a.id, area);
      e.reason.format("%s's route crosses %s first, in %.1f m: joins its coalition", a.name.c_str(), area_name(area),
                      a.crossings[0].entry);
      continue;
    }
    const Area* info = site_.area(area);
    Coalition fresh;
    fresh.area = area;
    fresh.type = info->type;
    fresh.started = now_;
    (void)fresh.agvs.push_back(a.id);
    (void)coalitions_.push_back(fresh);  // one per monitored area at most
    Event& e = event(EventType::coalition, a.id, area);
    e.reason.format("%s's route crosses %s (type %.*s) first, in %.1f m: coalition of %u", a.name.c_str(),
                    area_name(area), static_cast<int>(to_string(info->type).size()), to_string(info->type).data(),
                    a.crossings[0].entry, initial_size(info->type));
  }
}

void Centre::staff_coalitions() {
  for (Coalition& c : coalitions_) {
    const Area* area = site_.area(c.area);
    const AreaPeople people = people_.in_area(area->outline.as_span());
    const std::uint8_t before = c.wanted();
    if (c.observe(people_state(people))) {
      Event& e = event(EventType::coalition, kNone, c.area);
      e.reason.format("%u %s in %s (%u dynamic): %s people, final size %u (was %u)", people.count,
                      people.count == 1 ? "person" : "people", area_name(c.area), people.dynamic,
                      to_string(c.people).data(), c.wanted(), before);
    }
    const std::size_t wanted = c.wanted();

    // Too many: the member farthest from the area goes first.
    while (c.members.size() > wanted) {
      RobotSlot* far = nullptr;
      double far_d = -1;
      for (const RobotId m : c.members) {
        RobotSlot* r = robot(m);
        const double d = distance_to(area->outline.as_span(), position(r->last.pose));
        if (d >= far_d) {
          far = r;
          far_d = d;
        }
      }
      Event& e = event(EventType::release, kNone, c.area);
      (void)e.robots.push_back(far->id);
      e.reason.format("%s released from %s: %s people need %zu robot%s", far->name.c_str(), area_name(c.area),
                      to_string(c.people).data(), wanted, wanted == 1 ? "" : "s");
      remove_member(c, far->id);
      Reason why;
      why.format("released from %s", area_name(c.area));
      rest(*far, why.c_str());
    }
    if (c.members.size() >= wanted) {
      c.shortfall = 0;
      continue;
    }

    // Too few: Fig. 2.7 over every robot that may be taken.
    StaticVector<Candidate, kMaxRobots> candidates;
    for (const RobotSlot& r : robots_) {
      Candidate cand{r.id, position(r.last.pose), r.tasks.priority(), usable(r)};
      if (r.tasks.is(TaskKind::monitor) || r.tasks.is(TaskKind::charge) || coalition_of(r.id) != nullptr)
        cand.available = false;
      (void)candidates.push_back(cand);
    }
    const Selection chosen = select_robots(candidates.as_span(), area->outline.as_span(), wanted - c.members.size(),
                                           config_.allocation);
    const AgvId served = c.agvs.empty() ? kNone : c.agvs[0];
    for (const Swap& s : chosen.swaps) {
      Event& e = event(EventType::swap, served, c.area);
      (void)e.robots.push_back(s.taken);
      (void)e.robots.push_back(s.passed_over);
      e.reason.format("%s (idle, p = 2) taken for %s instead of the nearer %s (p = 1 work)", robot(s.taken)->name.c_str(),
                      area_name(c.area), robot(s.passed_over)->name.c_str());
    }
    const std::uint8_t priority = monitoring_priority(c.type);
    for (const RobotId id : chosen.robots) {
      RobotSlot& r = *robot(id);
      const Task monitor{next_task_id(), TaskKind::monitor, priority, sentry_pose(c, r), c.area, 0};
      Reason why;
      why.format("monitors %s for %s", area_name(c.area), agv_name(served));
      const double d = distance_to(area->outline.as_span(), position(r.last.pose));
      take(r, monitor, why.c_str());
      (void)c.members.push_back(id);
      Event& e = event(EventType::allocation, served, c.area);
      (void)e.robots.push_back(id);
      e.task = monitor.id;
      e.reason.format("%s, %.1f m away, %s (p = %u); coalition %zu of %zu", r.name.c_str(), d, why.c_str(), priority,
                      c.members.size(), wanted);
    }
    const auto shortfall = static_cast<std::uint8_t>(wanted - c.members.size());
    if (shortfall != c.shortfall && shortfall > 0) {
      Event& e = event(EventType::coalition, served, c.area);
      e.reason.format("%s has %zu of %zu robots: no other robot may be taken", area_name(c.area), c.members.size(), wanted);
    }
    c.shortfall = shortfall;
  }
}

void Centre::assign_requests() {
  // Urgent work first, then in order of arrival.
  std::stable_sort(pending_.begin(), pending_.end(),
                   [](const Pending& a, const Pending& b) { return a.request.priority < b.request.priority; });
  for (std::size_t i = 0; i < pending_.size();) {
    const Pending p = pending_[i];
    StaticVector<Candidate, kMaxRobots> candidates;
    for (const RobotSlot& r : robots_) {
      const auto& current = r.tasks.current();
      const bool free = !current || current->kind == TaskKind::home ||
                        (current->kind == TaskKind::amr && current->priority > p.request.priority);
      (void)candidates.push_back({r.id, position(r.last.pose), r.tasks.priority(), usable(r) && free});
    }
    const RobotId id = select_for_task(candidates.as_span(), position(p.request.goal));
    if (id == kNone) {
      ++i;
      continue;
    }
    RobotSlot& r = *robot(id);
    const Task work{p.task, TaskKind::amr, p.request.priority, p.request.goal, kNone, p.request.request};
    Reason why;
    why.format("AMR request %u (p = %u)", p.request.request, p.request.priority);
    take(r, work, why.c_str());
    Event& e = event(EventType::task);
    (void)e.robots.push_back(id);
    e.task = work.id;
    e.reason.format("%s takes %s", r.name.c_str(), why.c_str());
    pending_.erase(pending_.begin() + i);
  }
}

void Centre::idle_rule() {
  for (RobotSlot& r : robots_) {
    if (!r.online || !r.reported || r.tasks.current()) continue;
    if (r.tasks.suspended().empty())
      go_home(r, "idle");
    else
      rest(r, "idle");
  }
}

void Centre::advise() {
  for (AgvSlot& a : agvs_) {
    Advisory next;
    next.agv = a.id;
    for (const Crossing& x : a.crossings) {
      const AreaPeople people = people_.in_area(site_.area(x.area)->outline.as_span());
      if (!people.any()) continue;
      Advice advice = Advice::clear;
      if (people.any_dynamic() && x.entry <= config_.stop_distance)
        advice = Advice::stop;
      else if (x.entry <= config_.slow_distance)
        advice = Advice::slow;
      if (advice <= next.advice) continue;  // the nearest of the most severe wins
      next.advice = advice;
      next.area = x.area;
      next.people = people.count;
      next.dynamic = people.dynamic;
      next.distance = x.entry;
    }
    next.speed_factor = next.advice == Advice::clear ? 1.0 : next.advice == Advice::slow ? config_.slow_speed_factor : 0.0;

    const bool changed = !a.advised || next.advice != a.last.advice || next.area != a.last.area ||
                         next.people != a.last.people || next.dynamic != a.last.dynamic;
    if (!changed) continue;
    if (next.advice == Advice::slow) {
      next.reason.format("%u %s in %s, %.1f m ahead: slow to %.0f %%", next.people, next.people == 1 ? "person" : "people",
                         area_name(next.area), next.distance, 100 * next.speed_factor);
    } else if (next.advice == Advice::stop) {
      next.reason.format("%u %s in %s (%u moving), %.1f m ahead: stop", next.people, next.people == 1 ? "person" : "people",
                         area_name(next.area), next.dynamic, next.distance);
    } else if (a.advised && a.last.area != kNone) {
      const bool still_ahead = std::any_of(a.crossings.begin(), a.crossings.end(),
                                           [&](const Crossing& x) { return x.area == a.last.area; });
      next.reason.format("%s %s", area_name(a.last.area), still_ahead ? "is now empty" : "passed");
    } else {
      next.reason.assign("no people on the route ahead");
    }
    const AreaId about = next.area != kNone ? next.area : a.last.area;
    a.last = next;
    a.advised = true;
    if (!out_.advisories.push_back(next)) ++out_.dropped;
    Event& e = event(EventType::advisory, a.id, about);
    e.reason.format("%s: %.*s, %s", a.name.c_str(), static_cast<int>(to_string(next.advice).size()),
                    to_string(next.advice).data(), next.reason.c_str());
  }
}

// --- helpers -----------------------------------------------------------------------------

void Centre::take(RobotSlot& r, const Task& task, const char* why, bool send) {
  if (r.tasks.stack_full_for_new_task()) {
    // No room to keep the work: hand it back to the queue for another robot.
    const Task& work = *r.tasks.current();
    if (pending_.push_back({work.id, {work.request, work.priority, work.goal}})) {
      Event& e = event(EventType::task);
      (void)e.robots.push_back(r.id);
      e.task = work.id;
      e.reason.format("%s has no room to suspend task %u: requeued", r.name.c_str(), work.id);
    } else {
      ++out_.dropped;
    }
    r.tasks.finish();
  }
  const RobotTasks::Started started = r.tasks.start(task);
  Reason reason;
  if (started.suspended) {
    reason.format("%s: suspended for a %.*s task (p = %u)", why, static_cast<int>(to_string(task.kind).size()),
                  to_string(task.kind).data(), task.priority);
    command(CommandKind::suspend, r, *started.suspended, reason);
    Event& e = event(EventType::suspension);
    (void)e.robots.push_back(r.id);
    e.task = started.suspended->id;
    e.reason.format("%s suspends AMR task %u (p = %u): %s", r.name.c_str(), started.suspended->id,
                    started.suspended->priority, why);
  }
  if (!send) return;
  reason.assign(why);
  command(CommandKind::send, r, task, reason);
}

void Centre::rest(RobotSlot& r, const char* why) {
  r.tasks.finish();
  if (const std::optional<Task> resumed = r.tasks.resume()) {
    Reason reason;
    reason.format("%s: resumes its suspended work", why);
    command(CommandKind::resume, r, *resumed, reason);
    Event& e = event(EventType::resumption);
    (void)e.robots.push_back(r.id);
    e.task = resumed->id;
    e.reason.format("%s %s: resumes AMR task %u (p = %u)", r.name.c_str(), why, resumed->id, resumed->priority);
    return;
  }
  // Left idle: a waiting AMR request may take it in this very step, else the idle rule sends
  // it home, so it never gets two orders in one step.
}

void Centre::go_home(RobotSlot& r, const char* why) {
  const Task home{next_task_id(), TaskKind::home, kLowest, r.home, kNone, 0};
  (void)r.tasks.start(home);  // nothing current
  Reason reason;
  reason.format("%s: home (p = 2)", why);
  command(CommandKind::send, r, home, reason);
  Event& e = event(EventType::home);
  (void)e.robots.push_back(r.id);
  e.task = home.id;
  e.reason.format("%s %s: goes home to its charging station (p = 2)", r.name.c_str(), why);
}

void Centre::remove_member(Coalition& c, RobotId id) {
  c.members.remove_if([&](RobotId m) { return m == id; });
}

void Centre::command(CommandKind kind, const RobotSlot& r, const Task& task, const Reason& reason) {
  if (!out_.commands.push_back({kind, r.id, task, reason})) ++out_.dropped;
}

Event& Centre::event(EventType type, AgvId agv_id, AreaId area) {
  if (!out_.events.emplace_back()) {
    ++out_.dropped;
    scratch_ = Event{};
    return scratch_;
  }
  Event& e = out_.events.back();
  e.type = type;
  e.time = now_;
  e.agv = agv_id;
  e.area = area;
  return e;
}

Centre::RobotSlot* Centre::robot(RobotId id) noexcept {
  for (RobotSlot& r : robots_)
    if (r.id == id) return &r;
  return nullptr;
}

Centre::AgvSlot* Centre::agv(AgvId id) noexcept {
  for (AgvSlot& a : agvs_)
    if (a.id == id) return &a;
  return nullptr;
}

const char* Centre::area_name(AreaId id) const noexcept {
  const Area* a = site_.area(id);
  return a != nullptr ? a->name.c_str() : "?";
}

const char* Centre::agv_name(AgvId id) const noexcept {
  for (const AgvSlot& a : agvs_)
    if (a.id == id) return a.name.c_str();
  return "no AGV";
}

Coalition* Centre::coalition_of(RobotId id) noexcept {
  for (Coalition& c : coalitions_)
    if (std::find(c.members.begin(), c.members.end(), id) != c.members.end()) return &c;
  return nullptr;
}

const Coalition* Centre::coalition_at(AreaId area) const noexcept {
  for (const Coalition& c : coalitions_)
    if (c.area == area) return &c;
  return nullptr;
}

const RobotTasks* Centre::tasks(RobotId id) const noexcept {
  for (const RobotSlot& r : robots_)
    if (r.id == id) return &r.tasks;
  return nullptr;
}

std::optional<Advisory> Centre::advice(AgvId id) const noexcept {
  for (const AgvSlot& a : agvs_)
    if (a.id == id && a.advised) return a.last;
  return std::nullopt;
}

bool Centre::usable(const RobotSlot& r) const noexcept {
  return r.online && r.reported && r.last.battery >= config_.standing.low_battery;
}

// A robot whose home overlooks the area watches it from home; otherwise the first sentry pose
// no other member stands at.
Pose Centre::sentry_pose(const Coalition& c, const RobotSlot& r) const noexcept {
  if (r.overlooks == c.area) return r.home;
  const Area* area = site_.area(c.area);
  for (const Pose& p : area->sentries) {
    bool used = false;
    for (const RobotId m : c.members) {
      const RobotTasks* t = tasks(m);
      if (t != nullptr && t->current() && t->current()->goal == p) used = true;
    }
    if (!used) return p;
  }
  if (!area->sentries.empty()) return area->sentries.back();
  const Point mid = centroid(area->outline.as_span());
  return {mid.x_m, mid.y_m, 0};
}

}  // namespace sen3bot::ssc
