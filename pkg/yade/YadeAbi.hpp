// Declarations of the YADE 2023.02a classes this plugin derives from or reads, written from the
// binary facts in shared/doc/yade-abi.md (Debian ships no YADE headers). This is the ONLY file in
// the project that mirrors YADE's memory layout; every other file of pkg/yade includes it.
//
// How it works: every virtual function below is declared in YADE's slot order and never defined
// here, so vtables, typeinfo and bodies bind at load time to libyade.so's exported symbols. Every
// mirrored data member is checked with static_assert(offsetof) against the offsets read from
// libyade's exported constructors. A second, strict link (--no-undefined) in every build proves
// that each referenced symbol exists in libyade.so (see CMakeLists.txt).
//
// Compile with -DEIGEN_DONT_VECTORIZE -DEIGEN_DONT_ALIGN -DEIGEN_DISABLE_UNALIGNED_ARRAY_ASSERT:
// Debian built YADE with Eigen alignment off, which decides where Eigen members sit.
#pragma once

#if !defined(EIGEN_DONT_ALIGN) || !defined(EIGEN_DONT_VECTORIZE)
#error "pkg/yade must be compiled with EIGEN_DONT_ALIGN and EIGEN_DONT_VECTORIZE (YADE's Eigen layout)"
#endif

#include <boost/enable_shared_from_this.hpp>
#include <boost/python.hpp>
#include <boost/shared_ptr.hpp>
#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

// Exported by libyade as a global-namespace template (instances for ClassFactory and Omega).
template <class T> class Singleton {
public:
	static T& instance();
};

namespace yade {

using Real     = double; // yade.config.highPrecisionBits == 64 for yade-double
using Vector3r = Eigen::Matrix<Real, 3, 1>;

class Scene;
class State;
class Body;
class BodyContainer;
class TimingDeltas;
class BoundFunctor;
class InternalForceFunctor;
class Factorable;

// ---------------------------------------------------------------------------------------------
// Class factory (registration of plugin classes; exported, non-virtual).
class ClassFactory {
public:
	using CreateFactorableFnPtr = Factorable* (*)();
	using CreateSharedFactorableFnPtr = boost::shared_ptr<Factorable> (*)();
	using CreatePureCustomFnPtr = void* (*)();
	bool registerFactorable(std::string name, CreateFactorableFnPtr create, CreateSharedFactorableFnPtr createShared, CreatePureCustomFnPtr createPureCustom);
	void registerPluginClasses(const char* fileAndClasses[]);
};

// ---------------------------------------------------------------------------------------------
// Factorable: vptr @0, enable_shared_from_this weak_ptr @0x08; size 0x18. Vtable 56 B.
class Factorable : public boost::enable_shared_from_this<Factorable> {
public:
	Factorable() = default;
	virtual ~Factorable();
	virtual std::string getBaseClassName(unsigned int i = 0) const;
	virtual int         getBaseClassNumber() const;
	virtual std::string getClassName() const;
};

// Serializable: no data; vtable 112 B (slots 0..11).
class Serializable : public Factorable {
public:
	Serializable() = default;
	~Serializable() override;
	std::string                 getBaseClassName(unsigned int i = 0) const override;
	int                         getBaseClassNumber() const override;
	std::string                 getClassName() const override;
	virtual void                pySetAttr(const std::string& key, const boost::python::object& value);
	virtual boost::python::dict pyDict() const;
	virtual boost::python::dict pyDictCustom() const;
	virtual void                callPostLoad();
	virtual void                checkPyClassRegistersItself(const std::string& thisClassName) const;
	virtual void                pyRegisterClass(boost::python::object scope);
	virtual void                pyHandleCustomCtorArgs(boost::python::tuple& args, boost::python::dict& kw);
	// exported, non-virtual: calls pySetAttr for every key, then callPostLoad()
	void pyUpdateAttrs(const boost::python::dict& d);
	// member template not exported: only libyade's (o|i)serializer instances are used (extern below)
	template <class Archive> void serialize(Archive& ar, unsigned int version);
};

// Indexable: only a vptr (8 B). Its vtable is not exported, so bodies are inline/pure here; the
// slot order is the one of the secondary vtables of Shape/Material/State in libyade.
class Indexable {
public:
	Indexable() = default;
	virtual void       incrementMaxCurrentlyUsedClassIndexOfKin() = 0;
	virtual int&       modifyClassIndex() = 0;
	virtual ~Indexable() { }
	virtual const int& getClassIndex() const = 0;
	virtual const int& getBaseClassIndex(int depth) const = 0;
	virtual const int& getMaxCurrentlyUsedClassIndexOfKin() const = 0;

protected:
	// give this class a unique index among its kin on first construction (YADE's semantics)
	void createIndex()
	{
		int& index = modifyClassIndex();
		if (index == -1) {
			index = getMaxCurrentlyUsedClassIndexOfKin() + 1;
			incrementMaxCurrentlyUsedClassIndexOfKin();
		}
	}
};

// ---------------------------------------------------------------------------------------------
struct TimingInfo {
	long               nExec;
	unsigned long long nsec;
};

// Engine (size 0x68): vtable 128 B, slots 12 isActivated, 13 action.
class Engine : public Serializable {
public:
	Scene*                          scene;        // @0x18, set before each action()
	TimingInfo                      timingInfo;   // @0x20
	boost::shared_ptr<TimingDeltas> timingDeltas; // @0x30
	bool                            dead;         // @0x40
	int                             ompThreads;   // @0x44
	std::string                     label;        // @0x48

	Engine(); // exported: sets scene from Omega and the defaults
	~Engine() override;
	std::string                 getBaseClassName(unsigned int i = 0) const override;
	int                         getBaseClassNumber() const override;
	std::string                 getClassName() const override;
	void                        pySetAttr(const std::string& key, const boost::python::object& value) override;
	boost::python::dict         pyDict() const override;
	void                        callPostLoad() override;
	void                        pyRegisterClass(boost::python::object scope) override;
	virtual bool                isActivated();
	virtual void                action();
	template <class Archive> void serialize(Archive& ar, unsigned int version);
};

class GlobalEngine : public Engine {
public:
	GlobalEngine() = default;
	~GlobalEngine() override;
	std::string                 getBaseClassName(unsigned int i = 0) const override;
	int                         getBaseClassNumber() const override;
	std::string                 getClassName() const override;
	void                        pySetAttr(const std::string& key, const boost::python::object& value) override;
	boost::python::dict         pyDict() const override;
	void                        callPostLoad() override;
	void                        pyRegisterClass(boost::python::object scope) override;
	template <class Archive> void serialize(Archive& ar, unsigned int version);
};

// ---------------------------------------------------------------------------------------------
// Shape (size 0x60, FEMLIKE build): Serializable @0, Indexable @0x18. Vtable 224 B.
class Shape : public Serializable, public Indexable {
public:
	boost::shared_ptr<BoundFunctor>         boundFunctor;         // @0x20 (FEMLIKE)
	boost::shared_ptr<InternalForceFunctor> internalForceFunctor; // @0x30 (FEMLIKE)
	Vector3r                                color;                // @0x40
	bool                                    wire;                 // @0x58
	bool                                    highlight;            // @0x59

	Shape()
	        : color(1, 1, 1)
	        , wire(false)
	        , highlight(false)
	{
	}
	~Shape() override;
	std::string         getBaseClassName(unsigned int i = 0) const override;
	int                 getBaseClassNumber() const override;
	std::string         getClassName() const override;
	void                pySetAttr(const std::string& key, const boost::python::object& value) override;
	boost::python::dict pyDict() const override;
	void                callPostLoad() override;
	void                pyRegisterClass(boost::python::object scope) override;
	// new primary-vtable slots 12..16, in this order
	int&       modifyClassIndex() override;
	const int& getClassIndex() const override;
	const int& getBaseClassIndex(int depth) const override;
	const int& getMaxCurrentlyUsedClassIndexOfKin() const override;
	void       incrementMaxCurrentlyUsedClassIndexOfKin() override;
	template <class Archive> void serialize(Archive& ar, unsigned int version);
};

// ---------------------------------------------------------------------------------------------
// Material (size 0x50): Serializable @0, Indexable @0x18, id @0x20, label @0x28, density @0x48.
// Vtable 240 B: slots 12 newAssocState, 13 stateTypeOk, 14..18 index functions.
class Material : public Serializable, public Indexable {
public:
	int         id;      // @0x20, set by O.materials.append
	std::string label;   // @0x28
	Real        density; // @0x48 [kg m⁻³]

	Material()
	        : id(-1)
	        , density(1000)
	{
	}
	~Material() override;
	std::string                      getBaseClassName(unsigned int i = 0) const override;
	int                              getBaseClassNumber() const override;
	std::string                      getClassName() const override;
	void                             pySetAttr(const std::string& key, const boost::python::object& value) override;
	boost::python::dict              pyDict() const override;
	void                             callPostLoad() override;
	void                             pyRegisterClass(boost::python::object scope) override;
	virtual boost::shared_ptr<State> newAssocState() const;
	virtual bool                     stateTypeOk(State*) const;
	int&                             modifyClassIndex() override;
	const int&                       getClassIndex() const override;
	const int&                       getBaseClassIndex(int depth) const override;
	const int&                       getMaxCurrentlyUsedClassIndexOfKin() const override;
	void                             incrementMaxCurrentlyUsedClassIndexOfKin() override;
	template <class Archive> void    serialize(Archive& ar, unsigned int version);
};

// ---------------------------------------------------------------------------------------------
// Classes read through raw offsets only (never constructed or subclassed here).
namespace abi {
	constexpr std::size_t sceneDt                = 0x1b8; // Real
	constexpr std::size_t sceneIter              = 0x1c0; // long
	constexpr std::size_t sceneTime              = 0x1d0; // Real
	constexpr std::size_t sceneEngines           = 0x228; // vector<shared_ptr<Engine>>
	constexpr std::size_t sceneBodies            = 0x258; // shared_ptr<BodyContainer>
	constexpr std::size_t bodyContainerBodies    = 0x18;  // vector<shared_ptr<Body>>, null = erased
	constexpr std::size_t bodyId                 = 0x18;  // int
	constexpr std::size_t bodyMaterial           = 0x28;  // shared_ptr<Material>
	constexpr std::size_t bodyShape              = 0x48;  // shared_ptr<Shape>
	constexpr std::size_t bodyState              = 0x38;  // shared_ptr<State>
	// State (0x140): se3 @0x58 (56 B), vel @0x90, mass @0xa8, angVel @0xb0, angMom @0xc8, inertia
	// @0xe0, refPos @0xf8, refOri @0x110 (32 B), then blockedDOFs, isDamped, densityScaling
	constexpr std::size_t stateBlockedDofs       = 0x130; // unsigned; DOF_ALL = 63 is "not dynamic"
	constexpr unsigned    allDofsBlocked         = 63;

	template <class T> inline T& at(const void* base, std::size_t offset)
	{
		return *reinterpret_cast<T*>(reinterpret_cast<char*>(const_cast<void*>(base)) + offset);
	}
	inline Real&       dt(Scene* s) { return at<Real>(s, sceneDt); }
	inline long&       iter(Scene* s) { return at<long>(s, sceneIter); }
	inline Real&       time(Scene* s) { return at<Real>(s, sceneTime); }
	inline const auto& engines(Scene* s) { return at<std::vector<boost::shared_ptr<Engine>>>(s, sceneEngines); }
	inline const auto& bodies(Scene* s)
	{
		const auto& container = at<boost::shared_ptr<BodyContainer>>(s, sceneBodies);
		return at<std::vector<boost::shared_ptr<Body>>>(container.get(), bodyContainerBodies);
	}
	inline const boost::shared_ptr<Shape>&    shapeOf(const Body* b) { return at<boost::shared_ptr<Shape>>(b, bodyShape); }
	inline const boost::shared_ptr<Material>& materialOf(const Body* b) { return at<boost::shared_ptr<Material>>(b, bodyMaterial); }
	inline int                                idOf(const Body* b) { return at<int>(b, bodyId); }
	// Body::isDynamic(): not every degree of freedom blocked
	inline unsigned blockedDofsOf(const Body* b)
	{
		const auto& state = at<boost::shared_ptr<State>>(b, bodyState);
		return state ? at<unsigned>(state.get(), stateBlockedDofs) : allDofsBlocked;
	}
} // namespace abi

// The layout facts, checked at compile time.
static_assert(sizeof(Factorable) == 0x18, "Factorable size");
static_assert(sizeof(Serializable) == 0x18, "Serializable size");
static_assert(offsetof(Engine, scene) == 0x18, "Engine::scene");
static_assert(offsetof(Engine, timingInfo) == 0x20, "Engine::timingInfo");
static_assert(offsetof(Engine, timingDeltas) == 0x30, "Engine::timingDeltas");
static_assert(offsetof(Engine, dead) == 0x40, "Engine::dead");
static_assert(offsetof(Engine, ompThreads) == 0x44, "Engine::ompThreads");
static_assert(offsetof(Engine, label) == 0x48, "Engine::label");
static_assert(sizeof(Engine) == 0x68, "Engine size");
static_assert(sizeof(GlobalEngine) == 0x68, "GlobalEngine size");
static_assert(offsetof(Shape, boundFunctor) == 0x20, "Shape::boundFunctor");
static_assert(offsetof(Shape, internalForceFunctor) == 0x30, "Shape::internalForceFunctor");
static_assert(offsetof(Shape, color) == 0x40, "Shape::color");
static_assert(offsetof(Shape, wire) == 0x58, "Shape::wire");
static_assert(offsetof(Shape, highlight) == 0x59, "Shape::highlight");
static_assert(sizeof(Shape) == 0x60, "Shape size");
static_assert(offsetof(Material, id) == 0x20, "Material::id");
static_assert(offsetof(Material, label) == 0x28, "Material::label");
static_assert(offsetof(Material, density) == 0x48, "Material::density");
static_assert(sizeof(Material) == 0x50, "Material size");

} // namespace yade

// The base classes' serialize() templates are not exported by libyade; reuse libyade's exported
// serializer instances instead of instantiating them here. Include this header after the archive
// headers (see Serialization.hpp).
#define MPM_YADE_EXTERN_SERIALIZERS(Base)                                                                                  \
	extern template class boost::archive::detail::oserializer<boost::archive::binary_oarchive, yade::Base>;              \
	extern template class boost::archive::detail::iserializer<boost::archive::binary_iarchive, yade::Base>;              \
	extern template class boost::archive::detail::oserializer<boost::archive::xml_oarchive, yade::Base>;                 \
	extern template class boost::archive::detail::iserializer<boost::archive::xml_iarchive, yade::Base>;
