!> The data of a forming problem's contact, packed once into derived types by the api layer
!> (ddpy_api_forming) and passed whole to the contact (ddpy_forming) and the Newton loop
!> (ddpy_forming_newton): the tools with their surfaces and the blank faces that face them,
!> the (tool, slave node) pairs, the force-controlled tools, and per increment where the
!> tools are, the pairs' law and converged state, and the limits of the increment.
!>
!> Node indices (pair nodes, patch nodes, faces) are 0-based, as the Python model gives them
!> (ddpy.model.newton.Layout, ToolPack); tools are 1-based.
module ddpy_forming_data
  use ddpy_kinds, only: wp
  use ddpy_search_surface, only: search_surface
  implicit none
  private
  public :: contact_tool, tool_set, pair_set, force_holds, tool_placement, pair_law, &
            increment_limits, has_barrier, node_point

  !> Contact discretizations of a tool: node-to-surface (its slaves projected on it),
  !> surface-to-surface (gaps, normals and slips of the Gauss points of the blank faces
  !> averaged around each slave), Gauss-point contact (a penalty law at those Gauss points,
  !> its slaves' multipliers eliminated).
  integer, parameter, public :: contact_node = 0, contact_surface = 1, contact_gauss = 2
  !> The most Gauss points per direction of a blank face.
  integer, parameter, public :: max_face_order = 8

  !> One rigid tool: its surface and search (a copy of a ddpy_search_surface record), its
  !> facing direction (faced: it has one; its faces then are the blank's boundary faces
  !> that face it), its discretization, the Gauss points per direction of its faces
  !> (order: order x order per face) and its points' place in the flat point arrays
  !> (first_point, 0-based; npoint of them: order^2 per face, then one per slave for a
  !> Gauss-point tool, its node points); for Gauss-point contact the normal and tangential
  !> penalty (N/mm^3) and its barrier: barrier_depth (mm), the depth in the tool at which
  !> each slave node is held exactly (negative: none; docs/theory/contact.md, "The
  !> barrier").
  type :: contact_tool
    type(search_surface) :: surface
    logical :: faced = .false.
    real(wp) :: facing(3) = 0.0_wp
    integer :: discretization = contact_node
    integer :: order = 1
    integer :: first_point = 0, npoint = 0
    real(wp) :: normal_penalty = 0.0_wp, tangential_penalty = 0.0_wp
    real(wp) :: barrier_depth = -1.0_wp
  end type contact_tool

  !> The tools, one after another, with the blank faces of each: tool t's are
  !> face_first(t) + 1 .. face_first(t + 1) of faces (their 4 nodes) and corner (each
  !> corner's slave index in the tool, 0-based, -1 where not a slave); face_weight(i): the
  !> undeformed area point i stands for (its Gauss weight times the area element; a
  !> node point's: its slave's share of the faces' area).
  type :: tool_set
    integer :: ntool = 0, nface = 0, npoint = 0
    type(contact_tool), allocatable :: tool(:)
    integer, allocatable :: face_first(:)          !< (ntool + 1)
    integer, allocatable :: faces(:, :), corner(:, :)  !< (4, nface)
    real(wp), allocatable :: face_weight(:)        !< (npoint)
  end type tool_set

  !> The (tool, slave) pairs, tool after tool (tool t's are tool_first(t) + 1 ..
  !> tool_first(t + 1)): each pair's node, the nodes its law depends on (its patch:
  !> patch_first(p) + 1 .. patch_first(p + 1) of patch_node; its own node for a
  !> node-to-surface tool, the nodes of the tool's faces around it for the others), and
  !> held(c, p) = 1 where component c of its node is fixed (its law's row is lambda_c = 0).
  type :: pair_set
    integer :: npair = 0, npatch = 0
    integer, allocatable :: tool_first(:)          !< (ntool + 1)
    integer, allocatable :: node(:)                !< (npair)
    integer, allocatable :: patch_first(:)         !< (npair + 1)
    integer, allocatable :: patch_node(:)          !< (npatch)
    integer, allocatable :: held(:, :)             !< (3, npair)
  end type pair_set

  !> The force-controlled tools (ddpy_forming_newton): tool(k) presses along axis(:, k);
  !> the entries of its row are first(k) + 1 .. first(k + 1) of source (0-based slots of
  !> the contact blocks, -1: none) and coef, which the core's layout writes
  !> (ddpy_jacobian_layout).
  type :: force_holds
    integer :: nhold = 0, nsource = 0
    integer, allocatable :: tool(:)                !< (nhold)
    real(wp), allocatable :: axis(:, :)            !< (3, nhold)
    integer, allocatable :: first(:)               !< (nhold + 1)
    integer, allocatable :: source(:)              !< (nsource)
    real(wp), allocatable :: coef(:)               !< (nsource)
  end type force_holds

  !> Where the tools are in an increment (positions), where they were at the last
  !> converged increment (positions_n), and the force each force-controlled tool presses
  !> on the blank with (N).
  type :: tool_placement
    real(wp), allocatable :: positions(:, :), positions_n(:, :)  !< (3, ntool)
    real(wp), allocatable :: hold_force(:)                       !< (nhold)
  end type tool_placement

  !> The pairs' law in an increment: which take part (on = 1), their augmentation r and
  !> friction mu, and the tangential traction and pressure multiplier of every point of
  !> Gauss-point contact at the last converged increment.
  type :: pair_law
    integer, allocatable :: on(:)                  !< (npair)
    real(wp), allocatable :: r(:), mu(:)           !< (npair)
    real(wp), allocatable :: traction_n(:, :)      !< (3, npoint)
    real(wp), allocatable :: pressure_n(:)         !< (npoint)
  end type pair_law

  !> The limits an increment trial works within: the contact search's reach (mm), the
  !> blank's element size (mm), the touching predictor's gap (mm; 0: none) and whether it
  !> closes the touching pairs of tools at rest whatever the blank needs (resting), the
  !> penetration limit (element sizes) and the shortest step it may leave, the yield
  !> landing's tolerance (< 0: off), the size ratio (the phase's largest increment over
  !> this one's, >= 1), and the most a force-controlled tool moves in one step (mm).
  type :: increment_limits
    real(wp) :: reach = 0.0_wp, element_size = 0.0_wp, touching = 0.0_wp
    logical :: resting = .true.
    real(wp) :: penetration = 0.0_wp, min_step = 1.0_wp, yield_tolerance = -1.0_wp
    real(wp) :: size_ratio = 1.0_wp, hold_step = 0.0_wp
  end type increment_limits

contains

  !> Whether tool holds its slaves at a barrier (a Gauss-point tool with a barrier depth).
  pure logical function has_barrier(tool)
    type(contact_tool), intent(in) :: tool
    has_barrier = tool%discretization == contact_gauss .and. tool%barrier_depth >= 0.0_wp
  end function has_barrier

  !> The node point (in the flat point arrays) of pair p of Gauss-point tool t: the tool's
  !> points end with one per slave, in pair order.
  pure integer function node_point(tools, pairs, t, p)
    type(tool_set), intent(in) :: tools
    type(pair_set), intent(in) :: pairs
    integer, intent(in) :: t, p
    node_point = tools%tool(t)%first_point + tools%tool(t)%npoint - (pairs%tool_first(t + 1) - p)
  end function node_point

end module ddpy_forming_data
